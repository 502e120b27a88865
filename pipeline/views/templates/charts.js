/* The report's charts (views/charts.py): each element of class "chart" holds its
   figure as JSON ({data, layout, config}, plotly.js's own terms); drawn here once
   plotly.js is on the page (unpack.js) and the explorer drawn (explorer.js: the
   page's first plot; the charts come further down).  <body data-charts> says how
   many were drawn, for a headless browser's check. */
(function () {
  var first = window.explorerReady || Promise.resolve();
  first.catch(function () {}).then(function () { return window.plotlyReady; }).then(function () {
    var divs = Array.prototype.slice.call(document.querySelectorAll('div.chart'));
    var done = divs.map(function (div) {
      var spec = JSON.parse(div.querySelector('script.chart-data').textContent);
      return Plotly.newPlot(div, spec.data, spec.layout, spec.config);
    });
    return Promise.all(done).then(function () {
      document.body.dataset.charts = String(divs.length);
    });
  });
})();
