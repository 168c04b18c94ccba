/* bldclab report: small dependency-free SVG charts. Part of bldclab (MIT licence).
 *
 * Reads the JSON block <script id="bldclab-data">, draws every <figure class="plot" data-plot="ID"> from its
 * spec, and makes the waveform selector work. Interaction: hover for values, drag to zoom a box, Shift+drag to
 * pan, Ctrl+wheel to zoom about the cursor, double-click (or "reset") for the full view, click a legend entry to
 * hide or show its series.
 *
 * For testing, each figure records what was drawn: data-rendered ("ok" or "error"), data-series (visible series
 * with at least one point), data-points (points drawn) and data-error; <html> records data-plots-total,
 * data-plots-ok and data-js-errors (the count of errors caught on the page, whose messages are in
 * data-js-error-log).
 */
(function () {
  "use strict";

  var W = 640, H = 400, M = {l: 66, r: 18, t: 14, b: 50};
  var PW = W - M.l - M.r, PH = H - M.t - M.b;
  var HIT = 26;  // hover radius, px of the viewBox
  var nextId = 0;

  function record(message) {
    if (window.__bldclabRecord) { window.__bldclabRecord(message); return; }
    document.documentElement.setAttribute("data-js-errors", "1");
    document.documentElement.setAttribute("data-js-error-log", String(message));
  }

  function esc(s) {
    return String(s).replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;").replace(/"/g, "&quot;");
  }

  function fmt(v) {
    if (v === null || v === undefined || !isFinite(v)) { return "n/a"; }
    var a = Math.abs(v);
    if (a !== 0 && (a >= 1e6 || a < 1e-3)) { return v.toExponential(3); }
    return String(parseFloat(v.toPrecision(5)));
  }

  function niceStep(span, n) {
    var raw = span / n, mag = Math.pow(10, Math.floor(Math.log(raw) / Math.LN10)), r = raw / mag;
    return (r < 1.5 ? 1 : r < 3 ? 2 : r < 7 ? 5 : 10) * mag;
  }

  function ticks(lo, hi, n) {
    var step = niceStep(hi - lo, n), first = Math.ceil(lo / step - 1e-9), out = [];
    for (var k = first; k * step <= hi + step * 1e-9 && out.length < 50; k++) { out.push(k * step); }
    var decimals = Math.max(0, Math.min(10, -Math.floor(Math.log(step) / Math.LN10 + 1e-9)));
    return out.map(function (v) { return {v: v, label: (Math.abs(v) < step * 1e-9 ? 0 : v).toFixed(decimals)}; });
  }

  function column(table, name, tableName) {
    var c = table.data[name];
    if (!c) { throw new Error("table " + tableName + " has no column " + name); }
    return c;
  }

  /* Turn a series spec (table, x, y, where, scale) into arrays. */
  function resolve(spec, tables) {
    return spec.series.map(function (s) {
      var t = tables[s.table];
      if (!t) { throw new Error("no table " + s.table); }
      var xs = column(t, s.x, s.table), ys = column(t, s.y, s.table), where = s.where || {};
      var keys = Object.keys(where), cols = keys.map(function (k) { return column(t, k, s.table); });
      var x = [], y = [], scale = s.scale === undefined ? 1 : s.scale;
      for (var i = 0; i < xs.length; i++) {
        var keep = true;
        for (var k = 0; k < keys.length; k++) { if (cols[k][i] !== where[keys[k]]) { keep = false; break; } }
        if (!keep) { continue; }
        x.push(xs[i]);
        y.push(ys[i] === null || xs[i] === null ? null : ys[i] * scale);
      }
      return {name: s.name, x: x, y: y, color: s.color || "#333", line: s.line !== false, marker: s.marker || null,
              dash: s.dash || null, width: s.width || 1.6, hidden: !!s.hidden};
    });
  }

  function extent(series, spec) {
    var x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    series.forEach(function (s) {
      for (var i = 0; i < s.x.length; i++) {
        var x = s.x[i], y = s.y[i];
        if (x === null || y === null || !isFinite(x) || !isFinite(y)) { continue; }
        if (x < x0) { x0 = x; } if (x > x1) { x1 = x; }
        if (y < y0) { y0 = y; } if (y > y1) { y1 = y; }
      }
    });
    if (!isFinite(x0)) { x0 = 0; x1 = 1; y0 = 0; y1 = 1; }
    if (spec.xmin !== undefined && spec.xmin !== null) { x0 = spec.xmin; }
    if (spec.xmax !== undefined && spec.xmax !== null) { x1 = spec.xmax; }
    var pad = (y1 - y0) * 0.05 || Math.abs(y1) * 0.05 || 1;
    y0 -= pad; y1 += pad;
    if (spec.ymin !== undefined && spec.ymin !== null) { y0 = spec.ymin; }
    if (spec.ymax !== undefined && spec.ymax !== null) { y1 = spec.ymax; }
    if (!(x1 > x0)) { x1 = x0 + 1; }
    if (!(y1 > y0)) { y1 = y0 + 1; }
    return {x0: x0, x1: x1, y0: y0, y1: y1};
  }

  function markerPath(kind, px, py) {
    var r = 3.6;
    if (kind === "x") {
      return "M" + (px - r).toFixed(1) + " " + (py - r).toFixed(1) + "l" + (2 * r) + " " + (2 * r) + "m0 " + (-2 * r) +
        "l" + (-2 * r) + " " + (2 * r);
    }
    if (kind === "s") {
      return "M" + (px - r).toFixed(1) + " " + (py - r).toFixed(1) + "h" + (2 * r) + "v" + (2 * r) + "h" + (-2 * r) + "z";
    }
    return "M" + (px - r).toFixed(1) + " " + py.toFixed(1) + "a" + r + " " + r + " 0 1 0 " + (2 * r) + " 0a" + r + " " + r +
      " 0 1 0 " + (-2 * r) + " 0";
  }

  function clampPx(v) { return Math.max(-5000, Math.min(5000, v)); }

  function Plot(fig, spec, tables) {
    this.fig = fig;
    this.spec = spec;
    this.series = resolve(spec, tables);
    this.hidden = this.series.map(function (s) { return s.hidden; });
    this.full = extent(this.series, spec);
    this.view = {x0: this.full.x0, x1: this.full.x1, y0: this.full.y0, y1: this.full.y1};
    this.clip = "clip" + (nextId++);
    this.build();
    this.render();
  }

  Plot.prototype.build = function () {
    var self = this, fig = this.fig;
    var box = document.createElement("div");
    box.className = "plot-box";
    var tools = document.createElement("div");
    tools.className = "plot-tools";
    var reset = document.createElement("button");
    reset.type = "button";
    reset.textContent = "reset zoom";
    reset.addEventListener("click", function () { self.reset(); });
    tools.appendChild(reset);
    this.area = document.createElement("div");
    this.area.className = "plot-area";
    this.tip = document.createElement("div");
    this.tip.className = "plot-tip";
    this.tip.hidden = true;
    var legend = document.createElement("div");
    legend.className = "plot-legend";
    this.series.forEach(function (s, i) {
      var b = document.createElement("button");
      b.type = "button";
      b.className = "legend-item" + (self.hidden[i] ? " off" : "");
      b.setAttribute("aria-pressed", self.hidden[i] ? "false" : "true");
      b.title = "show or hide this series";
      var sw = '<svg class="swatch" viewBox="0 0 28 12" width="28" height="12">';
      if (s.line) {
        sw += '<path d="M1 6H27" stroke="' + esc(s.color) + '" stroke-width="2"' +
          (s.dash ? ' stroke-dasharray="' + esc(s.dash) + '"' : "") + "/>";
      }
      if (s.marker) {
        sw += '<path d="' + markerPath(s.marker, 14, 6) + '" stroke="' + esc(s.color) + '" fill="none" stroke-width="1.4"/>';
      }
      b.innerHTML = sw + "</svg>" + esc(s.name);
      b.addEventListener("click", function () {
        self.hidden[i] = !self.hidden[i];
        b.className = "legend-item" + (self.hidden[i] ? " off" : "");
        b.setAttribute("aria-pressed", self.hidden[i] ? "false" : "true");
        self.render();
      });
      legend.appendChild(b);
    });
    box.appendChild(tools);
    box.appendChild(this.area);
    box.appendChild(this.tip);
    box.appendChild(legend);
    var cap = fig.querySelector("figcaption");
    fig.insertBefore(box, cap);
    this.bindEvents();
  };

  Plot.prototype.sx = function (x) { var v = this.view; return M.l + (x - v.x0) / (v.x1 - v.x0) * PW; };
  Plot.prototype.sy = function (y) { var v = this.view; return M.t + PH - (y - v.y0) / (v.y1 - v.y0) * PH; };
  Plot.prototype.dx = function (px) { var v = this.view; return v.x0 + (px - M.l) / PW * (v.x1 - v.x0); };
  Plot.prototype.dy = function (py) { var v = this.view; return v.y0 + (M.t + PH - py) / PH * (v.y1 - v.y0); };

  Plot.prototype.render = function () {
    var self = this, spec = this.spec, v = this.view, out = [];
    out.push('<svg class="chart" viewBox="0 0 ' + W + " " + H + '" role="img" aria-label="' + esc(spec.title || "") + '">');
    out.push('<defs><clipPath id="' + this.clip + '"><rect x="' + M.l + '" y="' + M.t + '" width="' + PW + '" height="' +
      PH + '"/></clipPath></defs>');
    out.push('<rect class="bg" x="' + M.l + '" y="' + M.t + '" width="' + PW + '" height="' + PH + '"/>');
    var grid = [], labels = [];
    ticks(v.x0, v.x1, 7).forEach(function (t) {
      var px = self.sx(t.v).toFixed(1);
      grid.push("M" + px + " " + M.t + "V" + (M.t + PH));
      labels.push('<text class="tick" x="' + px + '" y="' + (M.t + PH + 16) + '" text-anchor="middle">' + t.label + "</text>");
    });
    ticks(v.y0, v.y1, 6).forEach(function (t) {
      var py = self.sy(t.v).toFixed(1);
      grid.push("M" + M.l + " " + py + "H" + (M.l + PW));
      labels.push('<text class="tick" x="' + (M.l - 6) + '" y="' + py + '" dy="0.32em" text-anchor="end">' + t.label + "</text>");
    });
    out.push('<path class="grid" d="' + grid.join("") + '"/>');
    out.push(labels.join(""));
    out.push('<g clip-path="url(#' + this.clip + ')">');
    (spec.vlines || []).forEach(function (l) {
      var px = self.sx(l.x).toFixed(1);
      out.push('<path class="vline" d="M' + px + " " + M.t + "V" + (M.t + PH) + '" stroke="' + esc(l.color || "#888") + '"' +
        (l.dash ? ' stroke-dasharray="' + esc(l.dash) + '"' : "") + "><title>" + esc(l.label + " = " + fmt(l.x)) + "</title></path>");
    });
    var nSeries = 0, nPoints = 0;
    this.series.forEach(function (s, i) {
      if (self.hidden[i]) { return; }
      var d = [], m = [], pen = false, n = 0;
      for (var k = 0; k < s.x.length; k++) {
        var x = s.x[k], y = s.y[k];
        if (x === null || y === null || !isFinite(x) || !isFinite(y)) { pen = false; continue; }
        var px = clampPx(self.sx(x)), py = clampPx(self.sy(y));
        if (s.line) { d.push((pen ? "L" : "M") + px.toFixed(1) + " " + py.toFixed(1)); pen = true; }
        if (s.marker && px >= M.l - 5 && px <= M.l + PW + 5 && py >= M.t - 5 && py <= M.t + PH + 5) {
          m.push(markerPath(s.marker, px, py));
        }
        n++;
      }
      if (n === 0) { return; }
      nSeries++;
      nPoints += n;
      if (d.length) {
        out.push('<path class="series series-line" data-series="' + i + '" d="' + d.join("") + '" stroke="' + esc(s.color) +
          '" stroke-width="' + s.width + '"' + (s.dash ? ' stroke-dasharray="' + esc(s.dash) + '"' : "") + "/>");
      }
      if (m.length) {
        out.push('<path class="series series-marker" data-series="' + i + '" d="' + m.join("") + '" stroke="' +
          esc(s.color) + '"/>');
      }
    });
    out.push("</g>");
    out.push('<rect class="frame" x="' + M.l + '" y="' + M.t + '" width="' + PW + '" height="' + PH + '"/>');
    out.push('<text class="axis-label" x="' + (M.l + PW / 2) + '" y="' + (H - 8) + '" text-anchor="middle">' +
      esc(spec.xlabel || "") + "</text>");
    out.push('<text class="axis-label" transform="translate(14 ' + (M.t + PH / 2) + ') rotate(-90)" text-anchor="middle">' +
      esc(spec.ylabel || "") + "</text>");
    out.push('<path class="cross" d="" visibility="hidden"/><circle class="hover" r="4.5" cx="0" cy="0" visibility="hidden"/>');
    out.push('<rect class="zoombox" x="0" y="0" width="0" height="0" visibility="hidden"/>');
    out.push('<rect class="hit" x="' + M.l + '" y="' + M.t + '" width="' + PW + '" height="' + PH + '"/>');
    out.push("</svg>");
    this.area.innerHTML = out.join("");
    this.svg = this.area.firstChild;
    this.fig.setAttribute("data-rendered", "ok");
    this.fig.setAttribute("data-series", String(nSeries));
    this.fig.setAttribute("data-points", String(nPoints));
  };

  Plot.prototype.reset = function () {
    this.view = {x0: this.full.x0, x1: this.full.x1, y0: this.full.y0, y1: this.full.y1};
    this.render();
  };

  /* Mouse position in viewBox units. */
  Plot.prototype.pos = function (ev) {
    var r = this.svg.getBoundingClientRect();
    return {x: (ev.clientX - r.left) * W / r.width, y: (ev.clientY - r.top) * H / r.height};
  };

  Plot.prototype.nearest = function (p) {
    var best = null, bestD = HIT * HIT, self = this;
    this.series.forEach(function (s, i) {
      if (self.hidden[i]) { return; }
      for (var k = 0; k < s.x.length; k++) {
        var x = s.x[k], y = s.y[k];
        if (x === null || y === null) { continue; }
        var ddx = self.sx(x) - p.x, ddy = self.sy(y) - p.y, d2 = ddx * ddx + ddy * ddy;
        if (d2 < bestD) { bestD = d2; best = {s: s, x: x, y: y}; }
      }
    });
    return best;
  };

  Plot.prototype.hover = function (p) {
    var svg = this.svg, hov = svg.querySelector(".hover"), cross = svg.querySelector(".cross");
    var inside = p.x >= M.l && p.x <= M.l + PW && p.y >= M.t && p.y <= M.t + PH;
    var hit = inside ? this.nearest(p) : null;
    if (!hit) {
      hov.setAttribute("visibility", "hidden");
      cross.setAttribute("visibility", "hidden");
      this.tip.hidden = true;
      return;
    }
    var px = this.sx(hit.x), py = this.sy(hit.y);
    hov.setAttribute("cx", px.toFixed(1));
    hov.setAttribute("cy", py.toFixed(1));
    hov.setAttribute("stroke", hit.s.color);
    hov.setAttribute("visibility", "visible");
    cross.setAttribute("d", "M" + px.toFixed(1) + " " + M.t + "V" + (M.t + PH));
    cross.setAttribute("visibility", "visible");
    this.tip.innerHTML = "<b>" + esc(hit.s.name) + "</b><br>" + esc(this.spec.xname || this.spec.xlabel || "x") + " = " +
      fmt(hit.x) + "<br>" + esc(this.spec.yname || this.spec.ylabel || "y") + " = " + fmt(hit.y);
    this.tip.hidden = false;
    var r = this.svg.getBoundingClientRect(), scale = r.width / W;
    var left = px * scale + 12, top = py * scale + 12;
    if (left > r.width - 200) { left = px * scale - 200; }
    this.tip.style.left = Math.max(0, left) + "px";
    this.tip.style.top = (top + this.area.offsetTop) + "px";
  };

  Plot.prototype.bindEvents = function () {
    var self = this, drag = null;
    this.area.addEventListener("mousemove", function (ev) {
      var p = self.pos(ev);
      if (drag) {
        if (drag.pan) {
          var fx = (p.x - drag.p.x) / PW * (drag.v.x1 - drag.v.x0), fy = (p.y - drag.p.y) / PH * (drag.v.y1 - drag.v.y0);
          self.view = {x0: drag.v.x0 - fx, x1: drag.v.x1 - fx, y0: drag.v.y0 + fy, y1: drag.v.y1 + fy};
          self.render();
          return;
        }
        var zb = self.svg.querySelector(".zoombox");
        var x = Math.max(M.l, Math.min(p.x, drag.p.x)), y = Math.max(M.t, Math.min(p.y, drag.p.y));
        zb.setAttribute("x", x.toFixed(1));
        zb.setAttribute("y", y.toFixed(1));
        zb.setAttribute("width", (Math.min(M.l + PW, Math.max(p.x, drag.p.x)) - x).toFixed(1));
        zb.setAttribute("height", (Math.min(M.t + PH, Math.max(p.y, drag.p.y)) - y).toFixed(1));
        zb.setAttribute("visibility", "visible");
        return;
      }
      self.hover(p);
    });
    this.area.addEventListener("mouseleave", function () {
      if (!drag) { self.hover({x: -1, y: -1}); }
    });
    this.area.addEventListener("mousedown", function (ev) {
      if (ev.button !== 0) { return; }
      var p = self.pos(ev);
      if (p.x < M.l || p.x > M.l + PW || p.y < M.t || p.y > M.t + PH) { return; }
      ev.preventDefault();
      drag = {p: p, pan: ev.shiftKey, v: {x0: self.view.x0, x1: self.view.x1, y0: self.view.y0, y1: self.view.y1}};
      self.hover({x: -1, y: -1});
    });
    window.addEventListener("mouseup", function (ev) {
      if (!drag) { return; }
      var d = drag;
      drag = null;
      if (d.pan) { return; }
      var p = self.pos(ev);
      var wx = Math.abs(p.x - d.p.x), wy = Math.abs(p.y - d.p.y);
      if (wx < 5 && wy < 5) { self.render(); return; }
      var xa = Math.max(M.l, Math.min(p.x, d.p.x)), xb = Math.min(M.l + PW, Math.max(p.x, d.p.x));
      var ya = Math.max(M.t, Math.min(p.y, d.p.y)), yb = Math.min(M.t + PH, Math.max(p.y, d.p.y));
      var nv = {x0: self.view.x0, x1: self.view.x1, y0: self.view.y0, y1: self.view.y1};
      if (wx >= 5) { nv.x0 = self.dx(xa); nv.x1 = self.dx(xb); }
      if (wy >= 5) { nv.y0 = self.dy(yb); nv.y1 = self.dy(ya); }
      self.view = nv;
      self.render();
    });
    this.area.addEventListener("wheel", function (ev) {
      if (!(ev.ctrlKey || ev.metaKey)) { return; }
      ev.preventDefault();
      var p = self.pos(ev), f = ev.deltaY > 0 ? 1.25 : 0.8, cx = self.dx(p.x), cy = self.dy(p.y), v = self.view;
      self.view = {x0: cx - (cx - v.x0) * f, x1: cx + (v.x1 - cx) * f, y0: cy - (cy - v.y0) * f, y1: cy + (v.y1 - cy) * f};
      self.render();
    }, {passive: false});
    this.area.addEventListener("dblclick", function () { self.reset(); });
  };

  function selectors() {
    Array.prototype.forEach.call(document.querySelectorAll("[data-selector]"), function (sel) {
      var group = sel.getAttribute("data-selector");
      var panels = document.querySelectorAll('[data-group="' + group + '"]');
      function show(value) {
        Array.prototype.forEach.call(panels, function (p) { p.hidden = p.getAttribute("data-value") !== value; });
      }
      Array.prototype.forEach.call(sel.querySelectorAll("input"), function (inp) {
        inp.addEventListener("change", function () { if (inp.checked) { show(inp.value); } });
        if (inp.checked) { show(inp.value); }
      });
      sel.hidden = false;
    });
  }

  function main() {
    var root = document.documentElement, data, ok = 0;
    var figs = document.querySelectorAll("figure.plot[data-plot]");
    root.setAttribute("data-plots-total", String(figs.length));
    try {
      data = JSON.parse(document.getElementById("bldclab-data").textContent);
    } catch (e) {
      record("cannot read the embedded data: " + e.message);
      return;
    }
    Array.prototype.forEach.call(figs, function (fig) {
      var id = fig.getAttribute("data-plot");
      try {
        var spec = data.plots[id];
        if (!spec) { throw new Error("no plot spec " + id); }
        var plot = new Plot(fig, spec, data.tables);
        fig.bldclabPlot = plot;
        ok++;
      } catch (e) {
        fig.setAttribute("data-rendered", "error");
        fig.setAttribute("data-error", String(e && e.message || e));
        record("plot " + id + ": " + (e && e.message || e));
      }
    });
    root.setAttribute("data-plots-ok", String(ok));
    selectors();
    root.classList.add("js");
  }

  main();
}());
