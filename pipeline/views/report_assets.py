"""The report page's style sheet and script, inline in the page: the script
sorts the tables, drives the front explorer and records (in ``data-*``
attributes of <body>) whether every picture decoded, so that a headless
browser can check the page."""

CSS = """
body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; margin: 0 auto;
       max-width: 1180px; padding: 1.2em 2em 3em; color: #222; line-height: 1.4; }
h1 { font-size: 1.55em; margin-bottom: 0.1em; }
h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 1.8em; }
.sub { color: #555; margin-top: 0; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0; }
th, td { padding: 0.2em 0.6em; text-align: right; border-bottom: 1px solid #e4e4e4; }
th { background: #f3f3f3; }
td.l, th.l { text-align: left; white-space: nowrap; }
.wide { overflow-x: auto; max-width: 100%; }
img { max-width: 100%; height: auto; }
.cards { display: flex; flex-wrap: wrap; gap: 14px; }
.motion img { max-width: 48%; align-self: flex-start; }
.card { border: 1px solid #ddd; border-radius: 6px; padding: 8px; width: 350px; }
.card h3 { font-size: 0.95em; margin: 0.1em 0 0.3em; }
.card table { font-size: 0.78em; width: 100%; }
.kv td:first-child { text-align: left; color: #555; }
pre { background: #f7f7f7; border: 1px solid #ddd; padding: 0.8em; font-size: 0.8em;
      overflow-x: auto; }
.note { color: #555; font-size: 0.9em; }
tr.knee td { background: #fff4d6; }
table.sortable th { cursor: pointer; }
table.sortable th:hover { background: #e6eef8; }
#explorer { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
#explorer svg { border: 1px solid #ddd; background: #fff; }
#explorer circle.pt { fill: #9ab; fill-opacity: 0.55; cursor: pointer; }
#explorer circle.f1 { fill: #c22; fill-opacity: 0.9; }
#explorer circle.sel { stroke: #000; stroke-width: 2; }
#tip { position: absolute; pointer-events: none; background: #fffbe8; border: 1px solid #cc9;
       padding: 3px 6px; font-size: 0.8em; display: none; }
#design-panel { min-width: 320px; max-width: 520px; font-size: 0.9em; }
"""

SCRIPT = """
(function () {
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
  // the front explorer: hover a point for its numbers, click it for the design
  var data = document.getElementById('explorer-data');
  if (data) {
    var d = JSON.parse(data.textContent), tip = document.getElementById('tip');
    var panel = document.getElementById('design-panel');
    function label(k) {
      var p = d.points[k];
      return '#' + p.i + ' (front ' + (p.f || '-') + '): ' + d.objectives.map(function (o, j) {
        return o + ' ' + p.m[j].toPrecision(4) + (d.objective_units[j] && d.objective_units[j] !== '1' ? ' ' + d.objective_units[j] : '');
      }).join(', ');
    }
    function el(tag, text, cls) {   // text only: names and units never become markup
      var e = document.createElement(tag);
      if (text !== undefined) { e.textContent = text; }
      if (cls) { e.className = cls; }
      return e;
    }
    function show(k, circle) {
      var p = d.points[k], table = el('table', undefined, 'kv');
      function row(label, value) {
        var tr = el('tr'); tr.appendChild(el('td', label)); tr.appendChild(el('td', value));
        table.appendChild(tr);
      }
      d.objectives.forEach(function (o, j) {
        row(o + ' [' + d.objective_units[j] + ']', p.m[j].toPrecision(5));
      });
      d.names.forEach(function (n, j) { row(n + ' [' + d.units[j] + ']', p.v[j].toPrecision(5)); });
      var pic = d.drawings[String(p.i)];
      panel.textContent = '';
      panel.appendChild(el('h3', 'Candidate ' + p.i + (p.f ? ', front ' + p.f : '')));
      if (pic) {   // the embedded drawing and curves of a front-1 design
        var img = el('img');
        img.alt = 'design ' + p.i;
        img.setAttribute('src', pic);
        panel.appendChild(img);
      } else {
        panel.appendChild(el('p', 'Its drawing and curves: pipeline show ' + d.file +
                                  ' --candidate ' + p.i, 'note'));
      }
      panel.appendChild(table);
      panel.dataset.candidate = String(p.i);
      Array.prototype.forEach.call(document.querySelectorAll('#explorer circle.sel'), function (c) { c.classList.remove('sel'); });
      circle.classList.add('sel');
    }
    Array.prototype.forEach.call(document.querySelectorAll('#explorer circle.pt'), function (c) {
      var k = Number(c.dataset.k);
      c.addEventListener('mouseenter', function (e) {
        tip.textContent = label(k); tip.style.display = 'block';
        tip.style.left = (e.pageX + 12) + 'px'; tip.style.top = (e.pageY + 12) + 'px';
      });
      c.addEventListener('mouseleave', function () { tip.style.display = 'none'; });
      c.addEventListener('click', function () { show(k, c); });
    });
  }
  window.addEventListener('error', function () {
    document.body.dataset.jsErrors = String(Number(document.body.dataset.jsErrors || 0) + 1);
  });
  window.addEventListener('load', function () {
    var imgs = Array.prototype.slice.call(document.images);
    var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; }).length;
    document.body.dataset.imagesTotal = String(imgs.length);
    document.body.dataset.imagesOk = String(ok);
    document.body.dataset.imagesLoaded = (imgs.length > 0 && ok === imgs.length) ? 'true' : 'false';
  });
})();
"""
