/* granplate study page: draws the views from the page's JSON (study-data: the designs,
   study-figures: plotly figures built by granplate.study.explorer) and links them:
   hover names a design with units, a click opens its panel, a selection in one view
   (a box in a scatter plot, a range on a parallel-coordinates axis, the check boxes)
   filters the others and the table; the table sorts by any column. */
(function () {
  "use strict";
  var tScript = performance.now();
  var D = JSON.parse(document.getElementById("study-data").textContent);
  var F = JSON.parse(document.getElementById("study-figures").textContent);
  var designs = D.designs;
  var Q = {};
  D.parameters.concat(D.metrics).forEach(function (q) { Q[q.name] = q; });
  var what = D.kind === "optimization" ? "trial" : "design";
  var MAX_TABLE_ROWS = 500;
  var CONFIG = { responsive: true, displaylogo: false, modeBarButtonsToRemove: ["toImage", "sendDataToCloud"] };
  var filters = {};   /* view -> Set of design rows, or null */
  var plots = [];     /* {div, name}: the scatter plots the filters dim */
  var sortState = { col: 0, dir: 1 };

  function num(x) {
    var a = Math.abs(x);
    if (x !== 0 && (a >= 1e5 || a < 1e-3)) { return x.toExponential(3).replace(/\.?0+e/, "e"); }
    return String(Number(x.toPrecision(4)));
  }
  /* a value in the unit shown (Pa as MPa), with the unit unless dimensionless or text */
  function shown(v, name) {
    if (v === null || v === undefined) { return "-"; }
    if (typeof v !== "number") { return String(v); }
    var q = Q[name] || { factor: 1, unit: "-" };
    return num(v * q.factor) + (q.unit && q.unit !== "-" ? " " + q.unit : "");
  }
  function esc(s) {
    return String(s).replace(/[&<>"']/g, function (c) {
      return { "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c];
    });
  }
  function mainMetrics() {
    var m = Object.keys(D.directions || {});
    D.table.forEach(function (x) { if (m.indexOf(x) < 0) { m.push(x); } });
    return m;
  }
  /* hover text of a design: its number, parameters and main metrics, with units */
  function hoverText(i) {
    var d = designs[i];
    var lines = ["<b>" + what + " " + d.number + "</b>" + (d.ok ? "" : " (" + esc(d.status).slice(0, 60) + ")")
                 + (d.feasible === false ? " infeasible" : "") + (d.front ? " (front)" : "")];
    D.parameters.forEach(function (q) { lines.push(esc(q.name) + " = " + esc(shown(d.params[q.name], q.name))); });
    mainMetrics().forEach(function (m) {
      if (d.metrics[m] !== undefined) { lines.push(esc(m) + " = " + esc(shown(d.metrics[m], m))); }
    });
    return lines.join("<br>");
  }
  function withHover(fig) {
    fig.data.forEach(function (t) {
      if (t.type === "heatmap") {
        t.hovertext = t.customdata.map(function (row) { return row.map(function (i) { return i >= 0 ? hoverText(i) : ""; }); });
        t.hovertemplate = "%{hovertext}<extra></extra>";
      } else if (t.customdata) {
        t.hovertext = t.customdata.map(hoverText);
        t.hovertemplate = "%{hovertext}<extra></extra>";
        t.selected = { marker: { opacity: 1 } };
        t.unselected = { marker: { opacity: 0.12 } };
      }
    });
    return fig;
  }

  /* ------------------------------------------------------------------ filters */
  function visibleSet() {
    var s = null;
    Object.keys(filters).forEach(function (k) {
      var f = filters[k];
      if (!f) { return; }
      if (s === null) { s = new Set(f); } else { s = new Set(Array.from(s).filter(function (i) { return f.has(i); })); }
    });
    return s;
  }
  var everFiltered = false;
  function apply() {
    var s = visibleSet();
    everFiltered = everFiltered || s !== null;
    var n = s === null ? designs.length : s.size;
    document.getElementById("shown").textContent = n + " of " + designs.length + " " + what + "s shown";
    plots.forEach(function (p) {
      if (filters[p.name] || !everFiltered) { return; }  /* the view a selection was made in shows it itself */
      var idx = [], sel = [];
      p.div.data.forEach(function (t, k) {
        if (!t.customdata || t.type === "heatmap") { return; }
        idx.push(k);
        sel.push(s === null ? null : t.customdata.reduce(function (a, i, j) { if (s.has(i)) { a.push(j); } return a; }, []));
      });
      if (idx.length) { Plotly.restyle(p.div, { selectedpoints: sel }, idx); }
    });
    blankHeatCells(s);
    recolourParcoords();
    renderTable();
  }
  /* the heat maps show the other views' filters: cells of designs filtered out are left blank */
  var heatKey = "";
  function blankHeatCells(s) {
    var key = s === null ? "" : Array.from(s).sort(function (a, b) { return a - b; }).join(",");
    if (key === heatKey) { return; }
    heatKey = key;
    ["fig-main", "fig-heat"].forEach(function (id) {
      var div = document.getElementById(id);
      if (!div || !div.data) { return; }
      var idx = [], zs = [];
      div.data.forEach(function (t, k) {
        if (t.type !== "heatmap" || !t.customdata) { return; }
        if (!t.zFull) { t.zFull = t.z.map(function (row) { return row.slice(); }); }
        idx.push(k);
        zs.push(t.zFull.map(function (row, r) {
          return row.map(function (v, c) { var i = t.customdata[r][c]; return s !== null && i >= 0 && !s.has(i) ? null : v; });
        }));
      });
      if (idx.length) { Plotly.restyle(div, { z: zs }, idx); }
    });
  }
  /* the parallel coordinates show the other views' filters: lines filtered out there faint */
  var parcoordsKey = "";
  function recolourParcoords() {
    var pc = document.getElementById("fig-parcoords");
    if (!pc || !pc.data || !F.parcoords) { return; }
    var s = null;
    Object.keys(filters).forEach(function (k) {
      var f = filters[k];
      if (!f || k === "parcoords") { return; }
      s = s === null ? new Set(f) : new Set(Array.from(s).filter(function (i) { return f.has(i); }));
    });
    var key = s === null ? "" : Array.from(s).sort(function (a, b) { return a - b; }).join(",");
    if (key === parcoordsKey) { return; }
    parcoordsKey = key;
    var colour = F.parcoords.rows.map(function (i, j) {
      return s !== null && !s.has(i) ? 0.5 : F.parcoords.data[0].line.color[j];
    });
    Plotly.restyle(pc, { "line.color": [colour] });
  }
  function setFilter(name, set) { filters[name] = set; apply(); }
  function linkSelection(div, name) {
    plots.push({ div: div, name: name });
    div.on("plotly_selected", function (ev) {
      if (!ev || !ev.points) { setFilter(name, null); return; }
      setFilter(name, new Set(ev.points.map(function (p) { return p.customdata; })));
    });
    div.on("plotly_deselect", function () { setFilter(name, null); });
  }
  function linkClick(div) {
    div.on("plotly_click", function (ev) {
      if (!ev || !ev.points || !ev.points.length) { return; }
      var i = ev.points[0].customdata;
      if (typeof i === "number" && i >= 0) { showDesign(i); }
    });
  }
  function parcoordsFilter(div) {
    var rows = F.parcoords.rows;
    var dims = div.data[0].dimensions;
    var s = null;
    dims.forEach(function (dim) {
      var r = dim.constraintrange;
      if (!r || !r.length) { return; }
      var ranges = Array.isArray(r[0]) ? r : [r];
      var keep = new Set();
      dim.values.forEach(function (v, j) {
        if (ranges.some(function (x) { return v >= x[0] && v <= x[1]; })) { keep.add(rows[j]); }
      });
      s = s === null ? keep : new Set(Array.from(s).filter(function (i) { return keep.has(i); }));
    });
    setFilter("parcoords", s);
  }

  /* ------------------------------------------------------------------ the design panel */
  function showDesign(i) {
    var d = designs[i];
    var panel = document.getElementById("panel");
    var rows = D.parameters.map(function (q) {
      return "<tr><td>" + esc(q.name) + "</td><td>" + esc(shown(d.params[q.name], q.name)) + "</td></tr>";
    });
    var metrics = mainMetrics().concat(D.metrics.map(function (q) { return q.name; }).filter(function (m) {
      return mainMetrics().indexOf(m) < 0;
    }));
    var mrows = metrics.filter(function (m) { return d.metrics[m] !== undefined; }).map(function (m) {
      return "<tr><td>" + esc(m) + "</td><td class='metric-value' data-metric='" + esc(m) + "'>"
        + esc(shown(d.metrics[m], m)) + "</td></tr>";
    });
    var figs = d.figures.map(function (f) {
      return "<figure><img alt='" + esc(f[0]) + "' src='" + esc(f[1]) + "'><figcaption>" + esc(f[0]) + "</figcaption></figure>";
    }).join("");
    var files = [];
    if (d.record) { files.push("<a href='" + esc(d.record) + "'>record</a>"); }
    if (d.result) { files.push("<a href='" + esc(d.result) + "'>result file</a>"); }
    panel.innerHTML = "<button class='close' type='button' title='close'>&times;</button>"
      + "<h2 id='panel-title' data-design='" + d.number + "'>" + what.charAt(0).toUpperCase() + what.slice(1) + " " + d.number + "</h2>"
      + "<p>" + (d.ok ? "ran to its end" : "no result: " + esc(d.status))
      + (d.feasible === false ? "; infeasible (constraints)" : d.feasible === true ? "; feasible" : "")
      + (d.front ? "; on the Pareto front" : "") + (d.why ? "; " + esc(d.why) : "")
      + (d.same_as !== null ? "; the same design as " + what + " " + designs[d.same_as].number : "") + ".</p>"
      + "<h3>Parameters</h3><table>" + rows.join("") + "</table>"
      + (mrows.length ? "<h3>Metrics</h3><table>" + mrows.join("") + "</table>" : "")
      + (figs ? "<h3>Figures</h3>" + figs : "<p class='hint'>Figures are drawn for the chosen designs "
                + "(the best of each objective); this one has its numbers only.</p>")
      + "<p class='hint'>key " + esc(d.key.slice(0, 12)) + (files.length ? ": " + files.join(", ") : " (no record kept beside this page)") + "</p>";
    panel.hidden = false;
    panel.querySelector(".close").addEventListener("click", function () { panel.hidden = true; });
  }

  /* ------------------------------------------------------------------ the table */
  function columns() {
    var cols = [{ head: what, value: function (d) { return d.number; }, text: function (d) {
      return d.number + (d.best.length ? "<span class='mark'>best " + esc(d.best.join(", ")) + "</span>" : "")
        + (d.front ? "<span class='mark'>front</span>" : ""); } }];
    D.parameters.forEach(function (q) {
      cols.push({ head: q.name + (q.numeric ? " [" + q.unit + "]" : ""), value: function (d) { return d.params[q.name]; },
                  text: function (d) { var v = d.params[q.name]; return esc(typeof v === "number" ? num(v * q.factor) : v); } });
    });
    D.table.forEach(function (m) {
      var q = Q[m];
      cols.push({ head: m + " [" + q.unit + "]", value: function (d) { return d.metrics[m]; },
                  text: function (d) { var v = d.metrics[m]; return v === undefined || v === null ? "-" : esc(num(v * q.factor)); } });
    });
    if (D.constraints.length) {
      cols.push({ head: "feasible", value: function (d) { return d.feasible === null ? null : d.feasible ? 1 : 0; },
                  text: function (d) { return d.feasible === null ? "-" : d.feasible ? "yes" : "no"; } });
    }
    cols.push({ head: "status", value: function (d) { return d.ok ? "ok" : d.status; },
                text: function (d) { return d.ok ? "ok" : esc(d.status === "not run" ? "not run" : "failed"); } });
    return cols;
  }
  var COLS = columns();
  function compare(a, b) {
    var none = function (v) { return v === null || v === undefined; };
    if (none(a) && none(b)) { return 0; }
    if (none(a)) { return 1; }
    if (none(b)) { return -1; }
    if (typeof a === "number" && typeof b === "number") { return (a - b) * sortState.dir; }
    return String(a).localeCompare(String(b)) * sortState.dir;
  }
  function renderTable() {
    var table = document.getElementById("designs");
    if (!table) { return; }
    var s = visibleSet();
    var col = COLS[sortState.col];
    var rows = designs.filter(function (d) { return d.same_as === null && (s === null || s.has(d.i)); });
    rows.sort(function (a, b) {
      var c = compare(col.value(a), col.value(b));
      return c !== 0 ? c : a.i - b.i;
    });
    var head = "<thead><tr>" + COLS.map(function (c, k) {
      var cls = k === sortState.col ? (sortState.dir > 0 ? "sorted-asc" : "sorted-desc") : "";
      return "<th data-col='" + k + "' class='" + cls + "'>" + esc(c.head) + "</th>";
    }).join("") + "</tr></thead>";
    var body = rows.slice(0, MAX_TABLE_ROWS).map(function (d) {
      return "<tr data-i='" + d.i + "' class='" + (d.feasible === false ? "infeasible" : "") + "'>"
        + COLS.map(function (c) { return "<td>" + c.text(d) + "</td>"; }).join("") + "</tr>";
    }).join("");
    var more = rows.length > MAX_TABLE_ROWS ? "<caption class='hint'>the first " + MAX_TABLE_ROWS + " of "
      + rows.length + " rows in this order: sort or filter to see others</caption>" : "";
    table.innerHTML = more + head + "<tbody>" + body + "</tbody>";
  }
  function linkTable() {
    var table = document.getElementById("designs");
    if (!table) { return; }
    table.addEventListener("click", function (ev) {
      var th = ev.target.closest("th");
      if (th) {
        var k = Number(th.getAttribute("data-col"));
        sortState = { col: k, dir: sortState.col === k ? -sortState.dir : 1 };
        renderTable();
        return;
      }
      var tr = ev.target.closest("tr[data-i]");
      if (tr) { showDesign(Number(tr.getAttribute("data-i"))); }
    });
  }
  /* the static tables of the page (targets, failures): sortable too */
  function sortableStatic() {
    document.querySelectorAll("table.sortable").forEach(function (table) {
      var dir = {};
      table.querySelectorAll("thead th").forEach(function (th, k) {
        th.addEventListener("click", function () {
          dir[k] = -(dir[k] || -1);
          var body = table.tBodies[0];
          var rows = Array.from(body.rows);
          rows.sort(function (a, b) {
            var x = a.cells[k].textContent, y = b.cells[k].textContent;
            var nx = parseFloat(x), ny = parseFloat(y);
            return (isNaN(nx) || isNaN(ny) ? x.localeCompare(y) : nx - ny) * dir[k];
          });
          rows.forEach(function (r) { body.appendChild(r); });
        });
      });
    });
  }

  /* ------------------------------------------------------------------ the best designs */
  function bestCards() {
    var box = document.getElementById("best");
    var order = Object.keys(D.directions || {});
    var rank = function (d) { return d.best.length ? order.indexOf(d.best[0]) : order.length; };
    var chosen = designs.filter(function (d) { return d.why; }).sort(function (a, b) { return rank(a) - rank(b) || a.i - b.i; });
    if (!chosen.length) { box.innerHTML = "<p class='hint'>No design completed yet.</p>"; return; }
    box.innerHTML = chosen.map(function (d) {
      var nums = Object.keys(D.directions || {}).filter(function (m) { return d.metrics[m] !== undefined; }).map(function (m) {
        return esc(m) + " = <b>" + esc(shown(d.metrics[m], m)) + "</b>";
      });
      var params = D.parameters.map(function (q) { return esc(q.name) + " = " + esc(shown(d.params[q.name], q.name)); });
      var thumbs = d.figures.filter(function (f) { return /assembly|energies/.test(f[0]); }).map(function (f) {
        return "<img alt='" + esc(f[0]) + "' src='" + esc(f[1]) + "'>";
      }).join("");
      return "<div class='card' data-i='" + d.i + "'><div class='text'><h3>" + what.charAt(0).toUpperCase() + what.slice(1) + " "
        + d.number + ": " + esc(d.why) + "</h3><p>" + nums.join(", ") + "</p><p class='params'>" + params.join(", ") + "</p></div>"
        + (thumbs ? "<div class='thumbs'>" + thumbs + "</div>" : "") + "</div>";
    }).join("");
    box.querySelectorAll(".card").forEach(function (c) {
      c.addEventListener("click", function () { showDesign(Number(c.getAttribute("data-i"))); });
    });
  }

  /* ------------------------------------------------------------------ the views */
  function draw(id, fig, name) {
    var div = document.getElementById(id);
    if (!div || !fig) { return null; }
    Plotly.newPlot(div, withHover(fig).data, fig.layout, CONFIG);
    linkClick(div);
    if (name) { linkSelection(div, name); }
    return div;
  }
  function metricChoice(div) {
    var sel = document.getElementById("metric-choice");
    if (!sel || !div) { return; }
    sel.innerHTML = D.drawn.map(function (m) {
      return "<option value='" + esc(m) + "'" + (m === F.metric.metric ? " selected" : "") + ">" + esc(m) + " [" + esc(Q[m].unit) + "]</option>";
    }).join("");
    sel.addEventListener("change", function () {
      var m = sel.value, q = Q[m];
      var ys = div.data.map(function (t) {
        return t.customdata.map(function (i) { var v = designs[i].metrics[m]; return v === undefined || v === null ? null : v * q.factor; });
      });
      Plotly.restyle(div, { y: ys });
      var upd = {};
      Object.keys(div.layout).forEach(function (k) {
        if (/^yaxis\d*$/.test(k) && div.layout[k].title && div.layout[k].title.text) { upd[k + ".title.text"] = m + " [" + q.unit + "]"; }
      });
      Plotly.relayout(div, upd);
    });
  }
  function heatChoice(div) {
    var msel = document.getElementById("heat-metric"), ssel = document.getElementById("heat-slice");
    if (!msel || !div || !F.heat) { return; }
    var index = F.heat.index;
    var metrics = index.map(function (x) { return x.metric; }).filter(function (m, k, a) { return a.indexOf(m) === k; });
    msel.innerHTML = metrics.map(function (m) { return "<option>" + esc(m) + "</option>"; }).join("");
    function slices() {
      return index.map(function (x, k) { return [x, k]; }).filter(function (p) { return p[0].metric === msel.value; });
    }
    function fillSlices() {
      ssel.innerHTML = slices().map(function (p) { return "<option value='" + p[1] + "'>" + esc(p[0].slice || "all") + "</option>"; }).join("");
      document.getElementById("heat-slice-label").hidden = slices().length < 2;
    }
    function show() {
      var k = Number(ssel.value);
      Plotly.restyle(div, { visible: index.map(function (x, j) { return j === k; }) });
    }
    msel.addEventListener("change", function () { fillSlices(); show(); });
    ssel.addEventListener("change", show);
    fillSlices();
  }

  /* draw a view below the first screen: now for a small study, when it comes near the
     window for a large one (the first screen is drawn first) */
  function later(div, drawIt) {
    if (!div) { return; }
    if (!D.gl || !("IntersectionObserver" in window)) { drawIt(); return; }
    var seen = new IntersectionObserver(function (entries) {
      if (entries.some(function (e) { return e.isIntersecting; })) { seen.disconnect(); drawIt(); }
    }, { rootMargin: "0px" });
    seen.observe(div);
  }
  var times = {};
  function mark(name) { times[name] = Math.round(performance.now()); }
  times.script = Math.round(tScript);
  function init() {
    var main = F.main;
    mark("parsed");
    var mainDiv = draw("fig-main", main ? F[main] : null, main === "heat" ? null : "main");
    if (main === "heat") { heatChoice(mainDiv); }
    if (main === "metric") { metricChoice(mainDiv); }
    mark("main");
    var pc = document.getElementById("fig-parcoords");
    if (pc && F.parcoords) {
      later(pc, function () {
        Plotly.newPlot(pc, F.parcoords.data, F.parcoords.layout, CONFIG);
        pc.on("plotly_restyle", function () { parcoordsFilter(pc); });
        mark("parcoords");
      });
    }
    if (main !== "metric") { later(document.getElementById("fig-metric"), function () {
      metricChoice(draw("fig-metric", F.metric, "metric")); mark("metric"); }); }
    if (main !== "heat") { later(document.getElementById("fig-heat"), function () {
      heatChoice(draw("fig-heat", F.heat, null)); mark("heat"); }); }
    var feasible = document.getElementById("only-feasible");
    feasible.disabled = !D.constraints.length;
    feasible.addEventListener("change", function () {
      setFilter("feasible", feasible.checked ? new Set(designs.filter(function (d) {
        return d.ok && d.feasible !== false; }).map(function (d) { return d.i; })) : null);
    });
    var front = document.getElementById("only-front");
    front.disabled = !designs.some(function (d) { return d.front; });
    front.addEventListener("change", function () {
      setFilter("front", front.checked ? new Set(designs.filter(function (d) { return d.front; }).map(function (d) { return d.i; })) : null);
    });
    document.getElementById("reset").addEventListener("click", function () {
      feasible.checked = false; front.checked = false;
      Object.keys(filters).forEach(function (k) { filters[k] = null; });
      plots.forEach(function (p) { Plotly.restyle(p.div, { selectedpoints: [null] }); });
      if (pc && pc.data) {
        Plotly.restyle(pc, F.parcoords.data[0].dimensions.reduce(function (u, d, k) {
          u["dimensions[" + k + "].constraintrange"] = null; return u; }, {}));
      }
      apply();
    });
    bestCards();
    linkTable();
    sortableStatic();
    apply();
    mark("ready");
    window.granplateExplorer = { showDesign: showDesign, setFilter: setFilter, visibleSet: visibleSet, data: D,
                                 times: times };
  }
  init();
})();
