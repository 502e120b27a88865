/* The report's explorer (explorer.html.j2), drawn with plotly.js from the data
   in #explorer-data (views/explorer.py): JSON, whose arrays ({dtype, offset,
   length}) are typed arrays viewing the binary block in #explorer-arrays, both
   packed (unpack.js).  Text from the study
   (names, units) goes into the page only as textContent, and to Plotly with <,
   > and & written as entities (Plotly reads a few tags in its labels). */
(function () {
  'use strict';
  var holder = document.getElementById('explorer-data');
  var plot = document.getElementById('ex-plot');
  if (!holder || !plot || !window.plotlyReady) { return; }
  // kept once the explorer is drawn (charts.js waits for it: the explorer first)
  window.explorerReady = Promise.all([
    window.plotlyReady, window.unpacked('explorer-data'), window.unpackedBytes('explorer-arrays')
  ]).then(function (got) {
    var D = JSON.parse(got[1]), block = got[2];
    function typed(spec) {     // little-endian, as in every browser
      return new ARRAYS[spec.dtype](block, spec.offset, spec.length);
    }
    D.ids = typed(D.ids);
    D.feasible = typed(D.feasible);
    D.columns.forEach(function (c) { c.values = typed(c.values); });
    return explorer(D);
  });

  var ARRAYS = {f4: Float32Array, f8: Float64Array, i1: Int8Array, u1: Uint8Array,
                i2: Int16Array, u2: Uint16Array, i4: Int32Array};
  function missing(v) { return v === null || v === undefined || v !== v; }   // NaN: no value

  function explorer(D) {
    var N = D.ids.length, Z = D.zoom_fronts;
    var col = {};
    D.columns.forEach(function (c) { col[c.key] = c; });
    var rank = col.front.values;            // Pareto front, 0: infeasible
    function $(id) { return document.getElementById(id); }
    var ui = {x: $('ex-x'), y: $('ex-y'), c: $('ex-c'), xlog: $('ex-xlog'), ylog: $('ex-ylog'),
              feas: $('ex-feas'), count: $('ex-count')};
    var bounds = Array.prototype.slice.call(document.querySelectorAll('.ex-filters input'));
    var panel = $('design-panel');
    // drawn in this order, the last on top; a click prefers the best front (pick)
    var TRACES = ['infeasible', 'feasible', 'fronts 2\u2013' + Z, 'front 1', 'knee',
                  'reference design', 'shown'];
    var FRONT = 3, NEAR = 2, CLOUD = 1, GREY = 0, REFERENCE = 5;
    var traceRows = [];        // per trace: the rows of D it draws (a click, a selection)
    var clicked = null;        // the row shown in the design panel ('reference' for it)
    var CONFIG = {responsive: true, scrollZoom: true, displaylogo: false,
                  doubleClick: 'reset+autosize'};
    var VIRIDIS = ['#440154', '#482878', '#3e4989', '#31688e', '#26828e', '#1f9e89',
                   '#35b779', '#6ece58', '#b5de2b', '#fde725'];
    var PICK_PX = 6;           // a click opens the best front's nearest design this close

    function plain(s) {         // a user's text for a Plotly label: never markup
      return String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
    }
    function unitText(c) { return c.unit && c.unit !== '1' ? ' [' + c.unit + ']' : ''; }
    function label(c) { return c.label + unitText(c); }
    function fmt(v) {
      if (missing(v)) { return '\u2013'; }
      return Number.isInteger(v) ? String(v) : Number(v).toPrecision(5);
    }
    function el(tag, text, cls) {
      var e = document.createElement(tag);
      if (text !== undefined && text !== null) { e.textContent = text; }
      if (cls) { e.className = cls; }
      return e;
    }
    function value(key, row) {
      if (row === 'reference') { return D.reference ? D.reference[key] : null; }
      return col[key].values[row];
    }
    function idOf(row) { return row === 'reference' ? 'reference' : String(D.ids[row]); }
    function palette(n) {
      var out = [];
      for (var k = 0; k < n; k++) { out.push(VIRIDIS[Math.round(k / Math.max(n - 1, 1) * 9)]); }
      return out;
    }

    // ------------------------------------------------------------ the scatter
    function filters() {
      var f = [];
      bounds.forEach(function (inp) {
        var v = parseFloat(inp.value);
        if (!isNaN(v)) { f.push({key: inp.dataset.key, min: inp.dataset.bound === 'min', v: v}); }
      });
      return f;
    }
    function passes(row, f) {
      for (var j = 0; j < f.length; j++) {
        var v = col[f[j].key].values[row];
        if (missing(v) || (f[j].min ? v < f[j].v : v > f[j].v)) { return false; }
      }
      return true;
    }
    function visibleRows() {
      var all = ui.feas.value === 'all', f = filters(), out = [];
      for (var k = 0; k < N; k++) {
        if ((all || D.feasible[k]) && passes(k, f)) { out.push(k); }
      }
      return out;
    }
    function column(key, rows) {
      var out = new Float64Array(rows.length);
      rows.forEach(function (k, j) { var v = value(key, k); out[j] = missing(v) ? NaN : v; });
      return out;
    }
    function trace(name, rows, xs, ys, extra) {
      var t = {name: name, x: column(xs, rows), y: column(ys, rows),
               text: rows.map(idOf), mode: 'markers',
               hovertemplate: '<b>#%{text}</b><br>' + plain(label(col[xs])) + ': %{x}<br>' +
                              plain(label(col[ys])) + ': %{y}<extra>' + name + '</extra>'};
      for (var k in extra) { t[k] = extra[k]; }
      return t;
    }
    // the axis range of fronts 1 to Z (all of them, whatever the filters: a view
    // that stays put while a bound is typed), a little wider; none: autorange
    function zoomRange(key, log) {
      var lo = Infinity, hi = -Infinity, v = col[key].values;
      for (var k = 0; k < N; k++) {
        if (rank[k] < 1 || rank[k] > Z || missing(v[k]) || (log && v[k] <= 0)) { continue; }
        var u = log ? Math.log10(v[k]) : v[k];
        if (u < lo) { lo = u; }
        if (u > hi) { hi = u; }
      }
      if (!(hi >= lo)) { return null; }
      var pad = 0.06 * (hi - lo || Math.abs(hi) || 1);
      return [lo - pad, hi + pad];
    }
    function axis(key, log) {
      var range = zoomRange(key, log), a = {title: {text: plain(label(col[key]))},
                                            type: log ? 'log' : 'linear'};
      if (range) { a.range = range; } else { a.autorange = true; }
      return a;
    }
    function update() {
      var xs = ui.x.value, ys = ui.y.value, cs = ui.c.value;
      var rows = visibleRows(), grey = [], feas = [], near = [], front = [];
      rows.forEach(function (k) {
        var f = rank[k];
        (f === 1 ? front : f >= 2 && f <= Z ? near : D.feasible[k] ? feas : grey).push(k);
      });
      var knee = rows.indexOf(D.knee) >= 0 ? [D.knee] : [];
      var ref = D.reference ? ['reference'] : [];
      var shown = clicked === null ? [] : [clicked];
      // the rest of the cloud dimmed behind fronts 1 to Z
      var cloud = {size: 4, color: '#7d97b3', opacity: 0.3};
      var nearby = {size: 7, color: '#e08a2c', opacity: 0.95, line: {color: '#7a4a12', width: 0.5}};
      if (cs) {
        var c = col[cs].values, lo = Infinity, hi = -Infinity;
        for (var k = 0; k < N; k++) {
          if (D.feasible[k] && !missing(c[k])) { lo = Math.min(lo, c[k]); hi = Math.max(hi, c[k]); }
        }
        var scale = {colorscale: 'Viridis', cmin: lo, cmax: hi};
        cloud = Object.assign({size: 4, opacity: 0.45, showscale: true, color: column(cs, feas),
                               colorbar: {title: {text: plain(label(col[cs])), side: 'right'},
                                          thickness: 14}}, scale);
        nearby = Object.assign({size: 7, opacity: 0.95, color: column(cs, near),
                                line: {color: '#000', width: 0.5}}, scale);
      }
      traceRows = [grey, feas, near, front, knee, ref, shown];
      // all WebGL: plotly.js draws its WebGL canvas over the SVG of the plot, so the
      // front, the knee and the reference design are WebGL traces too, drawn last (on top)
      var data = [
        trace(TRACES[0], grey, xs, ys, {type: 'scattergl', marker: {size: 3, color: '#bbbbbb',
                                                                       opacity: 0.35}}),
        trace(TRACES[1], feas, xs, ys, {type: 'scattergl', marker: cloud}),
        trace(TRACES[2], near, xs, ys, {type: 'scattergl', marker: nearby}),
        trace(TRACES[3], front, xs, ys, {type: 'scattergl', marker: {size: 9, color: '#c22222',
                                         line: {color: '#000', width: 0.6}}}),
        trace(TRACES[4], knee, xs, ys, {type: 'scattergl',
                                        marker: {size: 16, symbol: 'diamond-open', color: '#000',
                                                 line: {width: 2}}}),
        trace(TRACES[5], ref, xs, ys, {type: 'scattergl', marker: {size: 18, symbol: 'star',
                                       color: 'gold', line: {color: '#000', width: 1}}}),
        trace(TRACES[6], shown, xs, ys, {type: 'scattergl', showlegend: false,
                                         marker: {size: 20, symbol: 'circle-open', color: '#000',
                                                  line: {width: 2.5}}})
      ];
      var layout = {
        margin: {l: 70, r: 20, t: 30, b: 55}, hovermode: 'closest',
        xaxis: axis(xs, ui.xlog.checked), yaxis: axis(ys, ui.ylog.checked),
        legend: {orientation: 'h', x: 0, y: 1.06},
        uirevision: [xs, ys, ui.xlog.checked, ui.ylog.checked].join('|'),
        dragmode: plot._fullLayout ? plot._fullLayout.dragmode : 'zoom'
      };
      // what is drawn: the rows that pass and have a value on both axes
      var drawn = rows.filter(function (k) {
        var x = value(xs, k), y = value(ys, k);
        return !missing(x) && !missing(y) && (!ui.xlog.checked || x > 0) &&
               (!ui.ylog.checked || y > 0);
      }).length;
      var total = ui.feas.value === 'all' ? N : D.counts.feasible_shown;
      ui.count.textContent = drawn.toLocaleString('en') + ' of ' + total.toLocaleString('en') +
        ' designs shown (' + front.length + ' of front 1)' +
        (drawn < rows.length ? '; ' + (rows.length - drawn).toLocaleString('en') +
         ' more pass the filters but have no value on an axis' : '');
      ui.count.dataset.shown = String(drawn);
      return Plotly.react(plot, data, layout, CONFIG);
    }
    // the design a click opens: of the drawn designs within PICK_PX pixels of it, the
    // nearest of the best front (plotly.js alone gives any design whose marker covers
    // the click, often a worse neighbour's); none that close: the one plotly.js gives.
    // Pixels by plotly.js's own axis conversions (d2l, l2p, _offset: no public call)
    function pick(ev) {
      var e = ev && ev.event, fl = plot._fullLayout, best, bestRank = Infinity, bestD = PICK_PX;
      if (e && fl && fl.xaxis && fl.yaxis) {
        var xa = fl.xaxis, ya = fl.yaxis, box = plot.getBoundingClientRect();
        var px = e.clientX - box.left - xa._offset, py = e.clientY - box.top - ya._offset;
        var xs = ui.x.value, ys = ui.y.value;
        [FRONT, NEAR, CLOUD, GREY].forEach(function (t) {
          traceRows[t].forEach(function (k) {
            var x = value(xs, k), y = value(ys, k);
            if (missing(x) || missing(y)) { return; }
            var d = Math.hypot(xa.l2p(xa.d2l(x)) - px, ya.l2p(ya.d2l(y)) - py);
            var r = rank[k] >= 1 ? rank[k] : Infinity;     // infeasible: after every front
            if (d <= PICK_PX && (r < bestRank || (r === bestRank && d < bestD))) {
              best = k;
              bestRank = r;
              bestD = d;
            }
          });
        });
      }
      if (best !== undefined) { return best; }
      var p = ev && ev.points && ev.points[0];
      return p && traceRows[p.curveNumber] ? traceRows[p.curveNumber][p.pointIndex] : undefined;
    }

    // ------------------------------------------------------------ one design
    // the design's three small plots: zoom by drag, no tool bar over their titles
    var SMALL = {displaylogo: false, responsive: true, displayModeBar: false};
    var LEGEND = {orientation: 'h', x: 0, y: -0.2, yanchor: 'top', font: {size: 10}};
    function drawMechanism(div, m) {
      var n = m.x.length, pal = palette(n), data = [];
      Object.keys(m.paths).forEach(function (i) {
        data.push({x: m.paths[i][0], y: m.paths[i][1], mode: 'lines', hoverinfo: 'skip',
                   line: {color: '#999', width: 1, dash: 'dot'}, showlegend: false});
      });
      for (var k = n - 1; k >= 0; k--) {
        var x = [], y = [];
        m.segments.forEach(function (s) {
          x.push(m.x[k][s[0]], m.x[k][s[1]], null);
          y.push(m.y[k][s[0]], m.y[k][s[1]], null);
        });
        data.push({x: x, y: y, mode: 'lines', showlegend: false, opacity: k === 0 ? 1 : 0.6,
                   line: {color: pal[k], width: k === 0 ? 3 : 1.2},
                   hovertemplate: 'phi1 = ' + Number(m.phi[k]).toFixed(0) + ' deg<extra></extra>'});
      }
      var fixed = {};
      m.fixed.forEach(function (i) { fixed[i] = true; });
      data.push({x: m.x[0], y: m.y[0], mode: 'markers+text', showlegend: false,
                 text: m.names.map(plain), textposition: 'top right', textfont: {size: 10},
                 marker: {color: '#000',
                          size: m.names.map(function (_, i) { return fixed[i] ? 8 : 5; }),
                          symbol: m.names.map(function (_, i) {
                            return fixed[i] ? 'square' : 'circle';
                          })},
                 hovertemplate: '%{text}: (%{x}, %{y}) mm<extra></extra>'});
      return Plotly.newPlot(div, data, {
        title: {text: n + ' positions (thick: phi1 = ' + Number(m.phi[0]).toFixed(0) +
                      ' deg), dotted: paths', font: {size: 12}},
        margin: {l: 50, r: 10, t: 36, b: 40},
        xaxis: {title: {text: 'x [mm]'}}, yaxis: {title: {text: 'y [mm]'}, scaleanchor: 'x'}
      }, SMALL);
    }
    function drawMotion(div, m) {
      var data = [
        {x: m.phi, y: m.theta, mode: 'lines', name: 'rocker ' + plain(m.rocker) + ' [deg]',
         line: {color: '#000'}},
        {x: m.phi, y: m.dx, mode: 'lines', name: plain(m.working_point) + ' dx [mm]', yaxis: 'y2'},
        {x: m.phi, y: m.dy, mode: 'lines', name: plain(m.working_point) + ' dy [mm]', yaxis: 'y2'}
      ];
      var shapes = (m.dwell ? m.dwell.spans : []).map(function (s) {
        return {type: 'rect', xref: 'x', yref: 'paper', x0: s[0], x1: s[1], y0: 0, y1: 1,
                fillcolor: '#c22222', opacity: 0.12, line: {width: 0}};
      });
      return Plotly.newPlot(div, data, {
        title: {text: 'output motion' + (m.dwell ? ' (shaded: best ' + m.dwell.deg +
                                         ' deg dwell window)' : ''), font: {size: 12}},
        margin: {l: 50, r: 50, t: 36, b: 40}, shapes: shapes,
        legend: LEGEND,
        xaxis: {title: {text: 'crank angle phi1 [deg]'}, autorange: m.reversed ? 'reversed' : true},
        yaxis: {title: {text: 'rocker angle [deg]'}},
        yaxis2: {title: {text: 'displacement [mm]'}, overlaying: 'y', side: 'right',
                 showgrid: false, zeroline: false, tickmode: 'auto'}
      }, SMALL);
    }
    function drawReactions(div, r, reversed) {
      var data = r.joints.map(function (name, j) {
        return {x: r.phi, y: r.R[j], mode: 'lines', name: plain(name) + ' ' + fmt(r.peak[j]),
                hovertemplate: plain(r.where[j] || name) + '<br>|R| = %{y} N at phi1 = %{x} deg' +
                               '<extra>peak ' + fmt(r.peak[j]) + ' N</extra>'};
      });
      return Plotly.newPlot(div, data, {
        title: {text: 'joint reactions |R| at the operating speed (legend: peak, N)',
                font: {size: 12}},
        margin: {l: 55, r: 10, t: 36, b: 40}, legend: LEGEND,
        xaxis: {title: {text: 'crank angle phi1 [deg]'}, autorange: reversed ? 'reversed' : true},
        yaxis: {title: {text: '|R| [N]'}}
      }, SMALL);
    }
    function show(row) {
      var id = idOf(row), cycle = D.designs[id], knee = row === D.knee;
      var f = value('front', row);
      clicked = row;
      panel.textContent = '';
      panel.appendChild(el('h3', (row === 'reference' ? 'Reference design' : 'Candidate ' + id) +
                                 (f ? ', front ' + f : ', infeasible') +
                                 (knee ? ' (the knee)' : '')));
      var cmd = el('p', 'Its drawing, motion and reactions in full: ');
      cmd.appendChild(el('code', D.command + id, 'ex-command'));
      panel.appendChild(cmd);
      var done = [], box = null;
      if (cycle) {
        if (cycle.status !== 'OK') {
          panel.appendChild(el('p', cycle.status + ': ' + cycle.why, 'note'));
        }
        box = el('div', undefined, 'ex-drawings');
        var parts = [el('div'), el('div'), el('div')];
        parts.forEach(function (p) { box.appendChild(p); });
        panel.appendChild(box);
        done.push(drawMechanism(parts[0], cycle.mechanism), drawMotion(parts[1], cycle.motion));
        if (cycle.reactions) {
          done.push(drawReactions(parts[2], cycle.reactions, cycle.motion.reversed));
        } else {
          parts[2].appendChild(el('p', 'No reactions: the study has no mass data.', 'note'));
        }
      } else {
        panel.appendChild(el('p', 'No cycle embedded for this design (front-1 designs, the ' +
                                  'knee and the reference design have theirs): the command ' +
                                  'above draws it.', 'note'));
      }
      var table = el('table', undefined, 'kv');
      D.columns.forEach(function (c) {
        var tr = el('tr');
        tr.appendChild(el('td', label(c)));
        tr.appendChild(el('td', fmt(value(c.key, row))));
        table.appendChild(tr);
      });
      (box || panel).appendChild(table);
      panel.dataset.candidate = id;
      panel.dataset.drawn = 'pending';
      done.push(update());
      return Promise.all(done).then(function () {
        panel.dataset.drawn = cycle ? 'true' : 'false';
      });
    }

    // ------------------------------------------------------------ a selection
    var MAX_TABLE = 200, MAX_LINES = 20000;
    // the parallel coordinates' colours: a band per kind of design, as on the scatter.
    // plotly.js draws the line of the highest colour value on top (its depth), so the
    // best band has the highest: front 1 over fronts 2 to Z over the rest
    var BANDS = [['infeasible', '#d9d9d9'], ['other feasible', '#9fb6cf'],
                 ['fronts 2\u2013' + Z, '#e08a2c'], ['front 1', '#c22222']];
    var BAND_SCALE = [];
    BANDS.forEach(function (b, j) {
      BAND_SCALE.push([j / BANDS.length, b[1]], [(j + 1) / BANDS.length, b[1]]);
    });
    function band(row) {
      var f = rank[row];
      return f === 1 ? 3 : f >= 2 && f <= Z ? 2 : f >= 1 ? 1 : 0;
    }
    function byValue(values) {      // ascending, a missing value last
      return function (a, b) {
        var u = values[a], v = values[b];
        return missing(u) ? (missing(v) ? 0 : 1) : missing(v) ? -1 : u - v;
      };
    }
    function showSelection(rows) {
      var sec = $('ex-selection'), o = col[D.objectives[0]];
      if (!rows.length) {
        sec.classList.add('hidden');
        sec.dataset.rows = '0';
        return;
      }
      rows.sort(byValue(o.values));
      sec.classList.remove('hidden');
      var cols = [col.front].concat(D.objectives.map(function (k) { return col[k]; }),
                                    D.variables.map(function (k) { return col[k]; }));
      var table = $('ex-sel-table');
      table.textContent = '';
      var head = el('tr');
      head.appendChild(el('th', 'candidate'));
      cols.forEach(function (c) { head.appendChild(el('th', label(c))); });
      var thead = el('thead'), tbody = el('tbody');
      thead.appendChild(head);
      rows.slice(0, MAX_TABLE).forEach(function (k) {
        var tr = el('tr');
        tr.appendChild(el('td', idOf(k)));
        cols.forEach(function (c) { tr.appendChild(el('td', fmt(c.values[k]))); });
        tr.addEventListener('click', function () { show(k); });
        tbody.appendChild(tr);
      });
      table.appendChild(thead);
      table.appendChild(tbody);
      $('ex-sel-count').textContent = rows.length.toLocaleString('en') + ' designs selected' +
        (rows.length > MAX_TABLE ? ' (the table lists the first ' + MAX_TABLE + ' by ' +
         o.label + '; click a row for the design)' : ' (click a row for the design)');
      // the best first where the lines are too many for all of them
      var lines = rows.slice().sort(function (a, b) { return band(b) - band(a); })
        .slice(0, MAX_LINES);
      var dims = D.variables.map(function (k) {
        return {label: plain(label(col[k])),
                values: lines.map(function (r) { return col[k].values[r]; })};
      });
      sec.dataset.rows = String(rows.length);
      return Plotly.react($('ex-parcoords'), [{
        type: 'parcoords', dimensions: dims,
        line: {color: lines.map(band), colorscale: BAND_SCALE, cmin: -0.5,
               cmax: BANDS.length - 0.5, showscale: true,
               colorbar: {thickness: 14, tickvals: BANDS.map(function (b, j) { return j; }),
                          ticktext: BANDS.map(function (b) { return b[0]; })}}
      }], {margin: {l: 60, r: 130, t: 60, b: 30},
           title: {text: 'design variables of the selection (front 1 drawn on top)',
                   font: {size: 12}, y: 0.98}},
         {displaylogo: false, responsive: true}).then(function () {
        sec.dataset.parcoords = String(lines.length);
      });
    }

    // ------------------------------------------------------------ the report's designs
    // the representative designs' drawings and the design in motion, from the same
    // cycles as the explorer's (report.py writes the divs, data-design = the key)
    function where(m, i, k) {        // point i at path sample k (a fixed point stays)
      var p = m.paths[i];
      return p ? [p[0][k], p[1][k]] : [m.x[0][i], m.y[0][i]];
    }
    function linksAt(m, k) {
      var x = [], y = [];
      m.segments.forEach(function (s) {
        var a = where(m, s[0], k), b = where(m, s[1], k);
        x.push(a[0], b[0], null);
        y.push(a[1], b[1], null);
      });
      return {x: x, y: y};
    }
    function pointsAt(m, k) {
      return {x: m.names.map(function (_, i) { return where(m, i, k)[0]; }),
              y: m.names.map(function (_, i) { return where(m, i, k)[1]; })};
    }
    function animateMechanism(div, m, frames) {
      var keys = Object.keys(m.paths), n = keys.length ? m.paths[keys[0]][0].length : 1;
      var xs = [], ys = [];
      keys.forEach(function (i) { xs = xs.concat(m.paths[i][0]); ys = ys.concat(m.paths[i][1]); });
      m.x[0].forEach(function (v) { xs.push(v); });
      m.y[0].forEach(function (v) { ys.push(v); });
      function range(v) {
        var lo = Math.min.apply(null, v), hi = Math.max.apply(null, v), pad = 0.08 * (hi - lo || 1);
        return [lo - pad, hi + pad];
      }
      var data = keys.map(function (i) {
        return {x: m.paths[i][0], y: m.paths[i][1], mode: 'lines', hoverinfo: 'skip',
                showlegend: false, line: {color: '#bbb', width: 1, dash: 'dot'}};
      });
      var l0 = linksAt(m, 0), p0 = pointsAt(m, 0), moving = [data.length, data.length + 1];
      data.push({x: l0.x, y: l0.y, mode: 'lines', showlegend: false, hoverinfo: 'skip',
                 line: {color: '#1f4e99', width: 3}});
      data.push({x: p0.x, y: p0.y, mode: 'markers', showlegend: false, hoverinfo: 'skip',
                 marker: {color: '#000', size: 6}});
      var step = Math.max(1, Math.round(n / frames)), list = [];
      for (var k = 0; k < n; k += step) {
        var l = linksAt(m, k), p = pointsAt(m, k);
        list.push({name: String(k), traces: moving,
                   data: [{x: l.x, y: l.y}, {x: p.x, y: p.y}]});
      }
      var play = {frame: {duration: 50, redraw: false}, transition: {duration: 0},
                  fromcurrent: true, mode: 'immediate'};
      return Plotly.newPlot(div, data, {
        title: {text: 'one revolution, ' + list.length + ' frames (dotted: the paths)',
                font: {size: 12}, x: 0.98, xanchor: 'right'},
        margin: {l: 50, r: 10, t: 44, b: 40}, showlegend: false,
        xaxis: {title: {text: 'x [mm]'}, range: range(xs)},
        yaxis: {title: {text: 'y [mm]'}, range: range(ys), scaleanchor: 'x'},
        updatemenus: [{type: 'buttons', direction: 'left', showactive: false, x: 0, y: 1.0,
                       xanchor: 'left', yanchor: 'bottom', pad: {b: 4},
                       buttons: [{label: 'play', method: 'animate', args: [null, play]},
                                 {label: 'pause', method: 'animate',
                                  args: [[null], {mode: 'immediate', frame: {duration: 0}}]}]}]
      }, SMALL).then(function () {
        return Plotly.addFrames(div, list);
      }).then(function () {
        div.dataset.frames = String(list.length);
        // round and round: each time the revolution ends, from its first frame again
        var again = Object.assign({}, play, {fromcurrent: false});
        div.on('plotly_animated', function () { Plotly.animate(div, null, again); });
        Plotly.animate(div, null, play);
      });
    }
    function reportDesigns() {
      var done = [];
      Array.prototype.forEach.call(document.querySelectorAll('.design-drawing'), function (div) {
        var d = D.designs[div.dataset.design];
        if (d) { done.push(drawMechanism(div, d.mechanism)); }
      });
      Array.prototype.forEach.call(document.querySelectorAll('.design-animation'), function (div) {
        var d = D.designs[div.dataset.design];
        if (d) {
          done.push(animateMechanism(div, d.mechanism, Number(div.dataset.framesAsked || 60)));
        }
      });
      return Promise.all(done);
    }

    // ------------------------------------------------------------ wiring
    function rowsOf(points) {
      var seen = {}, out = [];
      (points || []).forEach(function (p) {
        var r = traceRows[p.curveNumber] && traceRows[p.curveNumber][p.pointIndex];
        if (r !== undefined && r !== 'reference' && p.curveNumber <= FRONT && !seen[r]) {
          seen[r] = true;
          out.push(r);
        }
      });
      return out;
    }
    ui.xlog.checked = !!col[ui.x.value].log;
    ui.ylog.checked = !!col[ui.y.value].log;
    ui.x.addEventListener('change', function () {
      ui.xlog.checked = !!col[ui.x.value].log;
      update();
    });
    ui.y.addEventListener('change', function () {
      ui.ylog.checked = !!col[ui.y.value].log;
      update();
    });
    [ui.c, ui.xlog, ui.ylog, ui.feas].forEach(function (e) {
      e.addEventListener('change', update);
    });
    bounds.forEach(function (e) { e.addEventListener('input', update); });
    var knee = $('ex-show-knee'), reference = $('ex-show-reference');
    if (knee) { knee.addEventListener('click', function () { show(D.knee); }); }
    if (reference) { reference.addEventListener('click', function () { show('reference'); }); }
    return update().then(function () {
      plot.on('plotly_click', function (ev) {
        var r = pick(ev);
        if (r !== undefined) { show(r); }
      });
      plot.on('plotly_selected', function (ev) { showSelection(rowsOf(ev && ev.points)); });
      plot.on('plotly_deselect', function () { showSelection([]); });
      // the page's width can change without the window's (a scroll bar appears as the
      // pictures decode): the plot follows its box, not only the window
      if (window.ResizeObserver) {
        new ResizeObserver(function () { Plotly.Plots.resize(plot); }).observe(plot);
      }
      // ready to use: the rest of the page (its designs here, the charts) draws after
      document.body.dataset.explorer = 'ready';
      reportDesigns().then(function () { document.body.dataset.designs = 'drawn'; });
    });
  }
})();
