/* The page's packed parts (views/page.py, packed): gzip written in base64,
   inflated by the browser's own DecompressionStream.  window.unpacked(id) and
   window.unpackedBytes(id): a promise of what element #id holds, as text or as
   an ArrayBuffer.  window.plotlyReady: a promise kept once
   plotly.js (#plotly-js) runs as a script of the page, as if it stood inline;
   the charts and the explorer wait for it. */
(function () {
  'use strict';
  // the inflated content of #id as a Response: .text(), .arrayBuffer()
  function inflated(id) {
    var text = document.getElementById(id).textContent.trim();
    // the browser's base64 (a data: address, never a fetch from outside the page)
    return fetch('data:application/gzip;base64,' + text).then(function (r) {
      return new Response(r.body.pipeThrough(new DecompressionStream('gzip')));
    });
  }
  window.unpacked = function (id) {
    return inflated(id).then(function (r) { return r.text(); });
  };
  window.unpackedBytes = function (id) {
    return inflated(id).then(function (r) { return r.arrayBuffer(); });
  };
  window.plotlyReady = window.unpacked('plotly-js').then(function (text) {
    var s = document.createElement('script');
    s.text = text;
    document.head.appendChild(s);
  });
})();
