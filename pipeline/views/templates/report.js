/* The report's own script: counts script errors, sorts the tables, and records
   (in data-* attributes of <body>) whether every picture decoded, so that a
   headless browser can check the page.  The explorer has its own (explorer.js). */
(function () {
  function counted() {
    document.body.dataset.jsErrors = String(Number(document.body.dataset.jsErrors || 0) + 1);
  }
  window.addEventListener('error', counted);
  window.addEventListener('unhandledrejection', counted);    // the scripts that wait on a promise
  // sortable tables: a click on a header sorts by that column (again: reversed)
  function cellValue(td) {
    var t = td.textContent.trim(), v = parseFloat(t);
    return isNaN(v) ? t : v;
  }
  Array.prototype.forEach.call(document.querySelectorAll('table.sortable'), function (table) {
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, col) {
      th.addEventListener('click', function () {
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var asc = th.dataset.order !== 'asc';
        rows.sort(function (a, b) {
          var x = cellValue(a.cells[col]), y = cellValue(b.cells[col]);
          return (x < y ? -1 : x > y ? 1 : 0) * (asc ? 1 : -1);
        });
        rows.forEach(function (r) { body.appendChild(r); });
        th.dataset.order = asc ? 'asc' : 'desc';
      });
    });
  });
  window.addEventListener('load', function () {
    var imgs = Array.prototype.slice.call(document.images);
    var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
    document.body.dataset.imagesTotal = String(imgs.length);
    document.body.dataset.imagesOk = String(ok);
    document.body.dataset.imagesLoaded = (imgs.length > 0 && ok === imgs.length) ? 'true' : 'false';
  });
})();
