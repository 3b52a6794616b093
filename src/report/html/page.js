// report.html: sortable and filterable tables, 3-D views (plotly.js, vendored), and a self-test
// (`report.html?selftest`) that the browser test reads back from the page's <body> attributes.
(function () {
  "use strict";
  // The page's head starts collecting errors (a script that failed to load, an exception in the
  // plotting library) into window.somnurbsErrors before anything else runs.
  var errors = window.somnurbsErrors || [];
  window.somnurbsErrors = { push: function (m) { errors.push(m); show(); } };
  function show() {
    var pre = document.getElementById("script-errors");
    if (pre && errors.length) { pre.hidden = false; pre.textContent = "Script errors:\n" + errors.join("\n"); }
    document.body.setAttribute("data-errors", String(errors.length));
  }
  function recordError(msg) { window.somnurbsErrors.push(String(msg)); }
  show();
  var consoleError = console.error;
  console.error = function () { recordError("console.error: " + Array.prototype.join.call(arguments, " ")); consoleError.apply(console, arguments); };

  // ---- tables ----
  function cellKey(td) {
    var t = td.textContent.trim().replace(/\*/g, "");
    var frac = /^(-?\d+)\/(\d+)$/.exec(t);
    if (frac) { return { num: Number(frac[2]) > 0 ? Number(frac[1]) / Number(frac[2]) : NaN, text: t }; }
    var n = t.replace(/%$/, "");
    if (/^[-+]?(\d+\.?\d*|\.\d+)(e[-+]?\d+)?$/i.test(n)) { return { num: parseFloat(n), text: t }; }
    return { num: NaN, text: t };
  }
  function sortTable(table, col, th) {
    var tbody = table.tBodies[0];
    var rows = Array.prototype.slice.call(tbody.rows);
    var dir = th.getAttribute("aria-sort") === "ascending" ? "descending" : "ascending";
    var keys = rows.map(function (r) { return r.cells[col] ? cellKey(r.cells[col]) : { num: NaN, text: "" }; });
    var numeric = keys.every(function (k) { return k.text === "" || k.text === "-" || !isNaN(k.num); }) && keys.some(function (k) { return !isNaN(k.num); });
    var idx = rows.map(function (r, i) { return i; });
    var sign = dir === "ascending" ? 1 : -1;
    idx.sort(function (a, b) {
      var ka = keys[a], kb = keys[b], c;
      if (numeric) {
        var na = isNaN(ka.num), nb = isNaN(kb.num);
        if (na || nb) { c = na === nb ? 0 : (na ? 1 : -1); return c !== 0 ? c : a - b; }
        c = sign * (ka.num - kb.num);
      } else {
        c = sign * ka.text.localeCompare(kb.text, undefined, { numeric: true });
      }
      return c !== 0 ? c : a - b;
    });
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (h) { h.removeAttribute("aria-sort"); });
    th.setAttribute("aria-sort", dir);
    idx.forEach(function (i) { tbody.appendChild(rows[i]); });
  }
  function makeFilters(table) {
    var tbody = table.tBodies[0];
    var head = table.tHead.rows[0].cells;
    var bar = document.createElement("div");
    bar.className = "filters";
    var input = document.createElement("input");
    input.type = "search";
    input.placeholder = "filter rows";
    bar.appendChild(input);
    var selects = [];
    for (var c = 0; c < head.length; c++) {
      var seen = [];
      Array.prototype.forEach.call(tbody.rows, function (r) {
        var t = r.cells[c] ? r.cells[c].textContent.trim() : "";
        if (seen.indexOf(t) < 0) { seen.push(t); }
      });
      if (seen.length < 2 || seen.length > 8 || seen.length === tbody.rows.length) { continue; }
      var sel = document.createElement("select");
      sel.setAttribute("data-col", String(c));
      var all = document.createElement("option");
      all.value = "";
      all.textContent = head[c].textContent.trim() + ": all";
      sel.appendChild(all);
      seen.sort().forEach(function (v) { var o = document.createElement("option"); o.value = v; o.textContent = v; sel.appendChild(o); });
      bar.appendChild(sel);
      selects.push(sel);
    }
    var count = document.createElement("span");
    count.className = "note";
    bar.appendChild(count);
    function apply() {
      var q = input.value.trim().toLowerCase(), shown = 0;
      Array.prototype.forEach.call(tbody.rows, function (r) {
        var ok = q === "" || r.textContent.toLowerCase().indexOf(q) >= 0;
        selects.forEach(function (s) {
          var col = Number(s.getAttribute("data-col"));
          if (s.value !== "" && (!r.cells[col] || r.cells[col].textContent.trim() !== s.value)) { ok = false; }
        });
        r.hidden = !ok;
        if (ok) { shown++; }
      });
      count.textContent = shown + " of " + tbody.rows.length + " rows";
    }
    input.addEventListener("input", apply);
    selects.forEach(function (s) { s.addEventListener("change", apply); });
    apply();
    table.parentNode.parentNode.insertBefore(bar, table.parentNode);
  }
  Array.prototype.forEach.call(document.querySelectorAll("table.sortable"), function (table) {
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, col) {
      th.title = "click to sort";
      th.addEventListener("click", function () { sortTable(table, col, th); });
    });
    if (table.classList.contains("filterable")) { makeFilters(table); }
  });

  // ---- 3-D views ----
  function traces(view) {
    var out = [];
    view.traces.forEach(function (t) {
      if (t.kind === "surface") {
        out.push({ type: "surface", name: t.label, x: t.x, y: t.y, z: t.z, showscale: false, showlegend: true, opacity: 0.92,
          colorscale: [[0, t.colour], [1, t.colour]], surfacecolor: t.z.map(function (row) { return row.map(function () { return 0; }); }), cmin: 0, cmax: 1,
          contours: { x: { show: false }, y: { show: false }, z: { show: false } } });
      } else {
        out.push({ type: "scatter3d", mode: "markers", name: t.label, x: t.x, y: t.y, z: t.z, marker: { size: 2.5, color: t.colour } });
        if (t.lx && t.lx.length) {
          out.push({ type: "scatter3d", mode: "lines", name: t.label + " grid", x: t.lx, y: t.ly, z: t.lz, line: { width: 2, color: t.colour }, opacity: 0.6, connectgaps: false });
        }
      }
    });
    return out;
  }
  var layout = { margin: { l: 0, r: 0, t: 10, b: 0 }, scene: { aspectmode: "data" }, legend: { x: 0, y: 1 } };
  var pending = [];
  var viewSets = window.somnurbsViews || [];
  Array.prototype.forEach.call(document.querySelectorAll(".views3d"), function (box) {
    var folder = box.getAttribute("data-folder");
    var set = viewSets.filter(function (s) { return s.folder === folder; })[0];
    var plot = box.querySelector(".plot3d");
    var select = box.querySelector("select");
    if (!set || !set.views.length) { plot.textContent = "No 3-D views were found for this folder."; return; }
    if (typeof Plotly === "undefined") { recordError("the plotting library (vendor/) did not load"); return; }
    set.views.forEach(function (v, i) { var o = document.createElement("option"); o.value = String(i); o.textContent = v.title; select.appendChild(o); });
    function draw(i) {
      box.removeAttribute("data-drawn");
      return Plotly.react(plot, traces(set.views[i]), layout, { responsive: true, displaylogo: false })
        .then(function () { box.setAttribute("data-drawn", String(i)); });
    }
    select.addEventListener("change", function () { draw(Number(select.value)); });
    // The first box draws at once; the others when they come into sight (software WebGL is slow).
    if (!pending.length) {
      pending.push(draw(0));
    } else if ("IntersectionObserver" in window) {
      var seen = new IntersectionObserver(function (entries) {
        if (entries.some(function (e) { return e.isIntersecting; })) { seen.disconnect(); draw(0); }
      });
      seen.observe(box);
    } else {
      draw(0);
    }
  });

  // ---- self-test (report.html?selftest) ----
  function sortCheck() {
    // The first table with a numeric column of at least three distinct values: click its heading
    // twice and read the order back.
    var tables = document.querySelectorAll("table.sortable");
    for (var t = 0; t < tables.length; t++) {
      var table = tables[t], head = table.tHead.rows[0].cells;
      for (var c = 0; c < head.length; c++) {
        var vals = Array.prototype.map.call(table.tBodies[0].rows, function (r) { return r.cells[c] ? cellKey(r.cells[c]).num : NaN; });
        if (vals.length < 3 || vals.some(isNaN)) { continue; }
        if (vals.filter(function (v, i) { return vals.indexOf(v) === i; }).length < 3) { continue; }
        var read = function () { return Array.prototype.map.call(table.tBodies[0].rows, function (r) { return cellKey(r.cells[c]).num; }); };
        head[c].click();
        var up = read();
        head[c].click();
        var down = read();
        var ok = up.every(function (v, i) { return i === 0 || up[i - 1] <= v; }) && down.every(function (v, i) { return i === 0 || down[i - 1] >= v; }) && up[0] < up[up.length - 1];
        return { ok: ok, table: t, column: head[c].textContent.trim(), first: up[0], last: up[up.length - 1] };
      }
    }
    return { ok: false, why: "no numeric column to sort" };
  }
  function inked(box) {
    // Render the drawn view to an image and count the pixels that are not background.
    var plot = box.querySelector(".plot3d");
    return Plotly.toImage(plot, { format: "png", width: 400, height: 300 }).then(function (url) {
      return new Promise(function (resolve) {
        var img = new Image();
        img.onload = function () {
          var cv = document.createElement("canvas");
          cv.width = img.width; cv.height = img.height;
          var g = cv.getContext("2d");
          g.drawImage(img, 0, 0);
          var d = g.getImageData(0, 0, cv.width, cv.height).data, n = 0;
          for (var i = 0; i < d.length; i += 4) { if (d[i + 3] > 0 && (d[i] < 235 || d[i + 1] < 235 || d[i + 2] < 235)) { n++; } }
          resolve({ ink: n / (cv.width * cv.height), url: url });
        };
        img.onerror = function () { resolve({ ink: -1, url: "" }); };
        img.src = url;
      });
    });
  }
  if (/[?&]selftest\b/.test(location.search)) {
    var boxes = document.querySelectorAll(".views3d");
    Promise.all(pending).then(function () {
      return boxes.length ? inked(boxes[0]) : { ink: 0, url: "" };
    }).then(function (picture) {
      var ink = picture.ink;
      document.body.setAttribute("data-selftest-image", picture.url);
      var sort = sortCheck();
      var drawn = document.querySelectorAll(".views3d[data-drawn]").length;
      var result = { views: boxes.length, drawn: drawn, ink: ink, sort: sort, tables: document.querySelectorAll("table.sortable").length,
        filters: document.querySelectorAll(".filters").length, errors: errors };
      var pass = boxes.length > 0 && drawn >= 1 && ink > 0.01 && sort.ok && errors.length === 0;
      document.body.setAttribute("data-selftest-result", JSON.stringify(result));
      document.body.setAttribute("data-selftest", pass ? "pass" : "fail");
    }, function (e) {
      recordError("self-test: " + (e && e.message || e));
      document.body.setAttribute("data-selftest", "fail");
    });
  }
})();
