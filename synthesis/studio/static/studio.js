// agrisynth studio page: sliders -> /api/evaluate (coarse while dragging, fine on release) -> rule table and SVG.
// Talks to its own server only (the token travels in a header); draws with plain SVG.
"use strict";

const TOKEN = new URLSearchParams(location.search).get("token") || "";
const SVGNS = "http://www.w3.org/2000/svg";
const COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];

const state = {
  info: null, values: {}, given: {}, inflight: false, pending: null, evaluations: 0,
  current: null, baseline: null, frame: 0, timer: null, polling: null, solving: false,
};

async function api(path, body) {
  const options = { headers: { "X-Studio-Token": TOKEN } };
  if (body !== undefined) {
    options.method = "POST";
    options.headers["Content-Type"] = "application/json";
    options.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(path, options);
  } catch (err) {       // no answer at all: the server was stopped (Ctrl-C, SIGTERM) or the machine is gone
    serverGone();
    throw new Error(`the studio server at ${location.host} is not answering (stopped?): nothing on this page is ` +
                    `evaluated or solved any more; start \`agrisynth studio\` again and reload`);
  }
  if (document.body.dataset.solve === "gone") {   // the server answers again (restarted, or a blip): resume
    document.body.dataset.solve = "";
    setTimeout(poll, 0);
  }
  let data;
  try {
    data = await response.json();
  } catch (err) {       // not the studio's JSON (a proxy's or a crashed server's page)
    throw new Error(`the server answered ${response.status} ${response.statusText} without a studio answer`);
  }
  if (!response.ok) throw new Error(data.error || response.statusText);
  return data;
}

// the page can do nothing without its server: a solve it showed as running is no longer known to run
function serverGone() {
  clearTimeout(state.polling);
  state.solving = false;
  document.body.dataset.solve = "gone";
  for (const id of ["solve", "cancel"]) document.getElementById(id).disabled = true;
  const line = document.getElementById("solve-state");
  if (!line.textContent.startsWith("server stopped")) {
    line.textContent = `server stopped: the last state it sent was "${line.textContent}"`;
  }
}

function el(tag, attrs, text) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
}

function svg(tag, attrs) {
  const node = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  return node;
}

function fmt(v) {
  if (v === null || v === undefined) return "-";
  if (typeof v !== "number") return String(v);
  return Math.abs(v) >= 1e5 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(3) : Number(v.toPrecision(4)).toString();
}

function limitText(limit) {
  if (!Array.isArray(limit)) return fmt(limit);
  const [lo, hi] = limit;
  if (lo !== null && hi !== null) return lo === hi ? `= ${fmt(lo)}` : `${fmt(lo)} … ${fmt(hi)}`;
  if (lo !== null) return `≥ ${fmt(lo)}`;
  if (hi !== null) return `≤ ${fmt(hi)}`;
  return "-";
}

// ---- sliders --------------------------------------------------------------------------------------------
// variables of one list item (guide_way's control point j: spline.control[j]) share a fieldset; the items of
// one list (spline.control) share a scrolling box, so 24 control points do not push the buttons off the page
function containerOf(box, v) {
  if (!v.group) return box;
  const list = v.group.slice(0, v.group.lastIndexOf("["));
  let scroller = box.querySelector(`div.group-list[data-list="${list}"]`);
  if (!scroller) {
    scroller = el("div", { class: "group-list", "data-list": list });
    box.append(el("h3", {}, list), scroller);
  }
  let set = scroller.querySelector(`fieldset[data-group="${v.group}"]`);
  if (!set) {
    set = el("fieldset", { "data-group": v.group });
    set.append(el("legend", {}, v.group.slice(list.length)));
    scroller.append(set);
  }
  return set;
}

// the number an input box holds, NaN for none: an empty box, or one the browser cannot read ("-", "1e"), has value
// "", which Number() reads as 0
function typedNumber(input) {
  const typed = input.value.trim();
  return typed === "" || input.validity.badInput ? NaN : Number(typed);
}

function buildSliders() {
  const box = document.getElementById("sliders");
  box.replaceChildren();
  for (const v of state.info.variables) {
    const row = el("div", { class: v.free ? "var" : "var fixed", "data-var": v.name });
    const label = el("label", { for: `range-${v.name}`, title: v.name });
    v.name.split(".").forEach((part, i) => {          // a long dotted name (the picker's crank_rocker.l7) wraps at its dots
      if (i) label.append(".", document.createElement("wbr"));
      label.append(part);
    });
    row.append(label);
    const range = el("input", { type: "range", id: `range-${v.name}`, name: v.name });
    const number = el("input", { type: "number", id: `number-${v.name}`, name: v.name });
    const step = v.free ? stepOf(v) : null;
    for (const input of [range, number]) {
      if (v.free) {
        input.min = v.bounds[0]; input.max = v.bounds[1];
        input.step = "any";
      } else {
        input.disabled = true;
      }
      input.value = v.value;
    }
    showInBox(number, v.value);
    if (!v.free) { range.min = v.value - 1; range.max = v.value + 1; range.value = v.value; }
    if (v.free) {
      range.step = String(step);            // a drag moves by whole steps too
      range.dataset.step = String(step);
      range.addEventListener("keydown", (ev) => stepKey(ev, v, step, true));
      number.addEventListener("keydown", (ev) => stepKey(ev, v, step, false));
    }
    range.addEventListener("input", () => { setValue(v.name, Number(range.value)); request("coarse"); });
    range.addEventListener("change", () => { setValue(v.name, Number(range.value)); request("fine"); });
    number.addEventListener("change", () => {
      // refused like a value outside the bounds: the page's value kept and the reason shown
      const x = typedNumber(number);
      const why = !Number.isFinite(x) ? "the typed value is not a number"
        : (x < v.bounds[0] || x > v.bounds[1])
          ? `${number.value.trim()} lies outside its bounds [${fmt(v.bounds[0])}, ${fmt(v.bounds[1])}]`
          : null;
      if (why) {
        showInBox(number, state.values[v.name]);
        showError(`${v.name}: ${why}; kept ${fmt(state.values[v.name])}${v.unit ? " " + v.unit : ""}`);
        return;
      }
      setValue(v.name, x); request("fine");
    });
    row.append(range, number, el("span", { class: "unit" }, v.unit || ""));
    row.append(el("span", { class: "bounds" }, v.free
      ? `free in [${fmt(v.bounds[0])}, ${fmt(v.bounds[1])}]; key step ${fmt(step)} (shift ${fmt(10 * step)})`
      : (v.note || "fixed in the spec")));
    containerOf(box, v).append(row);
  }
}

// an arrow key's step: 1/200 of the bound range as 1, 2 or 5 x 10^k, at least 0.1 mm or 0.1 deg (finer is
// below what a drawing shows); shift moves 10 steps
function stepOf(v) {
  const span = v.bounds[1] - v.bounds[0];
  const step = span > 0 ? niceNearest(span / 200) : 1;
  return v.unit === "mm" || v.unit === "deg" ? Math.max(step, 0.1) : step;
}

// one step from the value the page holds (not from the slider's snapped position), within the bounds; the fine
// grid at once (a key press is a release)
function stepKey(ev, v, step, sideways) {
  const keys = sideways ? { ArrowUp: 1, ArrowRight: 1, ArrowDown: -1, ArrowLeft: -1 } : { ArrowUp: 1, ArrowDown: -1 };
  const direction = keys[ev.key];
  if (!direction) return;
  ev.preventDefault();
  const moved = state.values[v.name] + direction * step * (ev.shiftKey ? 10 : 1);
  const x = Math.min(v.bounds[1], Math.max(v.bounds[0], Number(moved.toPrecision(12))));
  if (x === state.values[v.name]) return;
  setValue(v.name, x);
  request("fine");
}

function setValue(name, x) {
  state.values[name] = x;
  const range = document.getElementById(`range-${name}`);
  const number = document.getElementById(`number-${name}`);
  if (Number(range.value) !== x) range.value = x;
  showInBox(number, x);
}

// a number box shows its value to 10 significant digits (28.50732638 mm, not a solve's 28.507326381426154: a
// tenth of a nanometre is below any drawing); the page computes with the exact value, which the box keeps in
// data-value (the shortest text that reads back as the same double, as Python's repr writes it)
const BOX_DIGITS = 10;
function showInBox(number, x) {
  number.dataset.value = String(x);
  number.value = Number.isFinite(x) ? String(Number(x.toPrecision(BOX_DIGITS))) : String(x);
}

function freeValues() {
  const out = {};
  for (const v of state.info.variables) if (v.free) out[v.name] = state.values[v.name];
  return out;
}

// ---- evaluation: one request in flight; the latest values go next (fine wins over coarse) -------------------
// body[data-busy] is "1" from a request until nothing is in flight or pending: the moment the page shows the
// answer for the sliders' values (tests wait for it)
function request(grid) {
  if (state.inflight) {
    if (state.pending !== "fine") state.pending = grid;
    return;
  }
  state.inflight = true;
  document.body.dataset.busy = "1";
  const began = performance.now();
  api("/api/evaluate", { values: freeValues(), grid })
    .then((data) => { render(data, performance.now() - began); })
    .catch((err) => { stale(String(err.message || err)); })
    .finally(() => {
      state.inflight = false;
      const next = state.pending;
      state.pending = null;
      if (next) request(next);
      else document.body.dataset.busy = "0";
    });
}

// no answer for the sliders' values: the table and drawing of earlier values must not stand beside them
function stale(message) {
  state.current = null;
  showError(message);
  renderTable({ rules: [], error: message });
  renderDrawing();
  document.getElementById("status").textContent = `not evaluated: ${message}`;
  document.body.dataset.grid = "none";
}

function showError(text) {
  const box = document.getElementById("error");
  box.hidden = !text;
  box.textContent = text || "";
}

function render(data, answerMs) {
  const began = performance.now();
  state.evaluations += 1;
  state.current = data;
  showError(data.error);
  renderTable(data);
  renderDrawing();
  const drawMs = performance.now() - began;
  document.getElementById("status").textContent =
    `${data.grid} grid (${data.grid_note || ""}): evaluated in ${data.ms.toFixed(1)} ms, answered ` +
    `${answerMs.toFixed(0)} ms after the input, drawn in ${drawMs.toFixed(0)} ms`;
  document.body.dataset.drawMs = drawMs.toFixed(1);
  document.body.dataset.grid = data.grid;
  document.body.dataset.evaluations = String(state.evaluations);
}

function renderTable(data) {
  const body = document.querySelector("#rules tbody");
  body.replaceChildren();
  const base = {};
  for (const r of (state.baseline && state.baseline.rules) || []) base[r.name] = r;
  let bad = 0;
  for (const r of data.rules) {
    const row = el("tr", { "data-rule": r.name, "data-satisfied": String(r.satisfied) });
    if (!r.satisfied) { row.className = "violated"; bad += 1; }
    const b = base[r.name];
    for (const [text, cls] of [[r.name], [fmt(r.value)], [limitText(r.limit)], [r.unit || ""], [fmt(r.margin)],
                               [b ? fmt(b.margin) : "-", b && !b.satisfied ? "base bad" : "base"], [r.note || ""]]) {
      row.append(el("td", cls ? { class: cls } : {}, text));
    }
    body.append(row);
  }
  const verdict = document.getElementById("verdict");
  // an operating range: the verdict is the nominal point's (as check says), never the range's
  const scope = data.scope ? ` ${data.scope}` : "";
  verdict.textContent = data.error ? "(not evaluated)" : (bad ? `${bad} violated` : "every rule satisfied") + scope;
  verdict.className = bad || data.error ? "bad" : "good";
}

// ---- drawing --------------------------------------------------------------------------------------------
// Every panel is drawn in the svg's own pixels (viewBox 0 0 width height, redrawn on resize): texts have a font
// size in px that is the size on screen, the axes carry ticks in the data's units (mm) at round values, and a
// scale bar says how long a round number of mm is.  The frame maps data (y up) to pixels (y down).
const MARGIN = { left: 64, right: 16, top: 34, bottom: 46 };   // the scale bar sits in the top margin
const TEXT_PX = 12;            // point, joint, tick and line labels
const TICK_PX = { x: 90, y: 60 };   // about one tick every 90 px across, 60 px up

// the 1, 2 or 5 x 10^k at or above raw (tick spacings, scale bars)
function niceAbove(raw) {
  const base = 10 ** Math.floor(Math.log10(raw));
  const m = raw / base;
  return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * base;
}

// the 1, 2 or 5 x 10^k nearest raw (slider steps)
function niceNearest(raw) {
  const base = 10 ** Math.floor(Math.log10(raw));
  const m = raw / base;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * base;
}

function extent(groups, surfaces) {
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  const add = (x, y) => {
    if (x === null || y === null || x === undefined || y === undefined) return;
    x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y);
  };
  for (const g of groups) {
    if (!g) continue;
    for (const l of g.lines || []) l.x.forEach((x, i) => add(x, l.y[i]));
    for (const p of g.points || []) add(p.x, p.y);
    for (const f of g.frames || []) for (const v of Object.values(f)) {
      if (isPlaced(v)) placedPoints(g, v).forEach((xy) => add(xy[0], xy[1])); else add(v[0], v[1]);
    }
  }
  for (const s of surfaces || []) add(s.at[0], s.at[1]);        // a surface's point is in view: so is its line
  if (!Number.isFinite(x0)) return [-1, -1, 1, 1];
  const pad = 0.05 * Math.max(x1 - x0, y1 - y0, 1);
  return [x0 - pad, y0 - pad, x1 + pad, y1 + pad];
}

// data -> pixels for one svg: equal scales (a drawing) or each axis its own (a chart); the data's box is centred
// and the axes span the whole plot area
function frameOf(root, box, equal) {
  // the size the resize observer last saw (reading clientWidth after the table changed costs a page layout)
  const size = root.size || (root.size = [root.clientWidth, root.clientHeight]);
  const width = Math.max(size[0], 200), height = Math.max(size[1], 150);
  const pw = width - MARGIN.left - MARGIN.right, ph = height - MARGIN.top - MARGIN.bottom;
  let [x0, y0, x1, y1] = box;
  let sx = pw / Math.max(x1 - x0, 1e-9), sy = ph / Math.max(y1 - y0, 1e-9);
  if (equal) {
    const s = Math.min(sx, sy);
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    [x0, x1, y0, y1] = [cx - pw / (2 * s), cx + pw / (2 * s), cy - ph / (2 * s), cy + ph / (2 * s)];
    sx = sy = s;
  }
  return {
    width, height, x0, x1, y0, y1, sx, sy, equal,
    left: MARGIN.left, top: MARGIN.top, right: width - MARGIN.right, bottom: height - MARGIN.bottom,
    px: (x) => MARGIN.left + (x - x0) * sx,
    py: (y) => MARGIN.top + (y1 - y) * sy,
  };
}

function text(x, y, label, attrs) {
  const t = svg("text", { x, y, "font-size": TEXT_PX, ...attrs });
  t.textContent = label;
  return t;
}

// ticks at the round values inside [lo, hi]
function ticks(lo, hi, pixels, spacing) {
  const step = niceAbove((hi - lo) / Math.max(2, pixels / spacing));
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push(Number(v.toPrecision(12)));
  return { step, values: out };
}

function drawAxes(root, f, xTitle, yTitle) {
  const g = svg("g", { class: "axes", fill: "#444" });
  const grid = svg("g", { class: "grid", stroke: "#ececec", "stroke-width": 1 });
  const tx = ticks(f.x0, f.x1, f.right - f.left, TICK_PX.x), ty = ticks(f.y0, f.y1, f.bottom - f.top, TICK_PX.y);
  for (const v of tx.values) {
    const x = f.px(v);
    grid.append(svg("line", { x1: x, y1: f.top, x2: x, y2: f.bottom }));
    g.append(svg("line", { x1: x, y1: f.bottom, x2: x, y2: f.bottom + 5, stroke: "#444" }));
    g.append(text(x, f.bottom + 18, fmt(v), { "text-anchor": "middle", class: "tick", "data-tick-x": v }));
  }
  for (const v of ty.values) {
    const y = f.py(v);
    grid.append(svg("line", { x1: f.left, y1: y, x2: f.right, y2: y }));
    g.append(svg("line", { x1: f.left - 5, y1: y, x2: f.left, y2: y, stroke: "#444" }));
    g.append(text(f.left - 8, y + 4, fmt(v), { "text-anchor": "end", class: "tick", "data-tick-y": v }));
  }
  g.append(svg("rect", { x: f.left, y: f.top, width: f.right - f.left, height: f.bottom - f.top, fill: "none",
    stroke: "#999" }));
  g.append(text((f.left + f.right) / 2, f.height - 8, xTitle, { "text-anchor": "middle", class: "axis-title" }));
  g.append(text(14, (f.top + f.bottom) / 2, yTitle, { "text-anchor": "middle", class: "axis-title",
    transform: `rotate(-90 14 ${(f.top + f.bottom) / 2})` }));
  root.append(grid, g);
  root.dataset.tickStep = `${tx.step} ${ty.step}`;
}

// a bar of a round length in mm, in the top margin over the plot area's right end: it never covers the drawing
function drawScaleBar(root, f) {
  const mm = niceAbove((f.x1 - f.x0) / 8);
  const length = mm * f.sx, x1 = f.right, x0 = x1 - length, y = f.top - 12;
  const g = svg("g", { class: "scale-bar", "data-scale-mm": mm, stroke: "#111", "stroke-width": 2 });
  g.append(svg("line", { x1: x0, y1: y, x2: x1, y2: y, "stroke-width": 3 }));
  for (const x of [x0, x1]) g.append(svg("line", { x1: x, y1: y - 5, x2: x, y2: y + 5 }));
  g.append(text(x0 - 8, y + 4, `${fmt(mm)} mm`, { "text-anchor": "end", stroke: "none", fill: "#111" }));
  root.append(g);
}

// ground, soil surface, seedbed: straight lines across the panel, each through a point at an angle, read from
// what the server sends (key points, the design's values) and the kind's frame (docs/ARCHITECTURE.md, Conventions)
const SURFACES = {
  // planting: P4 is where the claw path meets the soil surface (machine and ground frames); the seedbed bottom
  // passes through the seedbed point, tilted by the design's seedbed_tilt
  planting_fourbar: (panelId, group, values) => {
    const p = Object.fromEntries((group.points || []).map((q) => [q.name, q]));
    const out = [];
    if (p.P4) out.push({ name: "soil surface", at: [p.P4.x, p.P4.y], deg: 0, colour: "#8b4513" });
    if (panelId === "panel-main" && p.seedbed && typeof values.seedbed_tilt === "number") {
      out.push({ name: "seedbed bottom", at: [p.seedbed.x, p.seedbed.y], deg: values.seedbed_tilt, colour: "#2a8a2a" });
    }
    return out;
  },
  // tillage: the rollers C stand height_c above the ground (machine frame, C at the origin); the ground frame's y
  // is the height above the ground
  tillage_linkage: (panelId, group, values) => {
    if (panelId === "panel-ground") return [{ name: "ground", at: [0, 0], deg: 0, colour: "#8b4513" }];
    return typeof values.height_c === "number"
      ? [{ name: "ground", at: [0, -values.height_c], deg: 0, colour: "#8b4513" }] : [];
  },
  // comb_finger's front view: y up from the ground line
  comb_finger: (panelId) => (panelId === "panel-main" ? [{ name: "ground", at: [0, 0], deg: 0, colour: "#8b4513" }] : []),
};

function surfacesOf(panelId, group, values) {
  const recipe = state.info && SURFACES[state.info.kind];
  return recipe && group ? recipe(panelId, group, values || {}) : [];
}

function drawSurfaces(root, f, surfaces) {
  const reach = 4 * (f.x1 - f.x0 + f.y1 - f.y0);
  for (const s of surfaces) {
    const a = (s.deg * Math.PI) / 180, ux = Math.cos(a), uy = Math.sin(a);
    const g = svg("g", { class: "surface", "data-surface": s.name });
    g.append(svg("line", { x1: f.px(s.at[0] - reach * ux), y1: f.py(s.at[1] - reach * uy),
      x2: f.px(s.at[0] + reach * ux), y2: f.py(s.at[1] + reach * uy), stroke: s.colour, "stroke-width": 2 }));
    // the label where the line leaves the plot area on the right (or its bottom/top edge when steep)
    let t = (f.x1 - s.at[0]) / (Math.abs(ux) > 1e-9 ? ux : 1e-9);
    if (Math.abs(uy) > 1e-9) t = Math.min(t, ((uy > 0 ? f.y1 : f.y0) - s.at[1]) / uy);
    const lx = Math.min(f.px(s.at[0] + t * ux) - 4, f.right - 4), ly = f.py(s.at[1] + t * uy);
    g.append(text(lx, Math.min(Math.max(ly - 6, f.top + 14), f.bottom - 6), s.name,
      { "text-anchor": "end", fill: s.colour, class: "surface-label halo" }));
    root.append(g);
  }
}

// a label's x and anchor: right of its point, or left of it near the plot area's right edge (never cut off there)
function beside(f, x, gap) {
  return x > f.right - 90 ? [x - gap, "end"] : [x + gap, "start"];
}

function pathOf(xs, ys, f) {
  let d = "";
  xs.forEach((x, i) => {
    if (x === null || ys[i] === null) return;
    d += `${d && xs[i - 1] !== null && ys[i - 1] !== null ? "L" : "M"}${f.px(x).toFixed(1)},${f.py(ys[i]).toFixed(1)}`;
  });
  return d;
}

function drawGroup(root, group, f, ghost) {
  const g = svg("g", { class: ghost ? "baseline" : "current", opacity: ghost ? "0.35" : "1" });
  (group.lines || []).forEach((l, i) => {
    g.append(svg("path", { d: pathOf(l.x, l.y, f), fill: "none", "data-line": l.name,
      stroke: ghost ? "#888" : COLOURS[i % COLOURS.length], "stroke-width": l.main ? 2.2 : 1.4,
      "stroke-dasharray": ghost ? "5 4" : "" }));
  });
  for (const p of group.points || []) {
    if (p.x === null || p.y === null) continue;
    g.append(svg("circle", { cx: f.px(p.x), cy: f.py(p.y), r: 4, fill: ghost ? "#888" : "#d62728", "data-point": p.name }));
    if (!ghost) {
      const [x, anchor] = beside(f, f.px(p.x), 6);
      g.append(text(x, f.py(p.y) - 6, p.name, { fill: "#222", class: "point-label halo", "text-anchor": anchor }));
    }
  }
  root.append(g);
}

// a pose's value is a joint [x, y], or a placed shape {shape, at: [x, y], turn_deg}: one of the mechanism's rigid
// outlines (a cam's profile, a roller, a drum wall; sent once in mechanism.shapes, in the body's own frame) turned by
// turn_deg counter-clockwise about the body's origin and moved to ``at``
function isPlaced(v) {
  return v !== null && typeof v === "object" && !Array.isArray(v) && typeof v.shape === "string";
}

function placedPoints(mechanism, v) {
  const pts = (mechanism.shapes || {})[v.shape] || [];
  const a = ((v.turn_deg || 0) * Math.PI) / 180, c = Math.cos(a), s = Math.sin(a);
  return pts.filter((xy) => xy[0] !== null && xy[1] !== null)
    .map((xy) => [v.at[0] + c * xy[0] - s * xy[1], v.at[1] + s * xy[0] + c * xy[1]]);
}

function drawPose(root, mechanism, k, f, ghost) {
  const pose = mechanism.frames[k % mechanism.frames.length];
  const frame = {};
  const g = svg("g", { class: ghost ? "pose baseline" : "pose", opacity: ghost ? "0.35" : "1" });
  for (const [n, v] of Object.entries(pose)) {
    if (!isPlaced(v)) { frame[n] = v; continue; }
    const pts = placedPoints(mechanism, v).map((xy) => `${f.px(xy[0]).toFixed(1)},${f.py(xy[1]).toFixed(1)}`).join(" ");
    g.append(svg("polyline", { points: pts, fill: "none", stroke: ghost ? "#888" : "#333", "stroke-width": 2,
      "data-outline": n }));
  }
  const names = Object.keys(frame);
  const bars = mechanism.bars || names.slice(1).map((n, i) => [names[i], n]);
  for (const [a, b] of bars) {
    if (!frame[a] || !frame[b]) continue;
    g.append(svg("line", { x1: f.px(frame[a][0]), y1: f.py(frame[a][1]), x2: f.px(frame[b][0]), y2: f.py(frame[b][1]),
      stroke: ghost ? "#888" : "#333", "stroke-width": 3, "stroke-linecap": "round" }));
  }
  for (const n of names) {
    const [x, y] = [f.px(frame[n][0]), f.py(frame[n][1])];
    g.append(svg("circle", { cx: x, cy: y, r: 4.5, fill: "#fff", stroke: "#333", "stroke-width": 1.5, "data-joint": n }));
    if (!ghost) {
      const [lx, anchor] = beside(f, x, 7);
      g.append(text(lx, y + 16, n, { fill: "#444", class: "joint-label halo", "text-anchor": anchor }));
    }
  }
  root.append(g);
}

// drawn in the svg's pixels: an svg whose size changes (the window, the layout) is drawn again at its new size
let redrawing = 0;
const resized = new ResizeObserver((entries) => {
  let changed = false;
  for (const entry of entries) {
    const root = entry.target, box = entry.contentRect;
    if (!root.size || root.size[0] !== box.width || root.size[1] !== box.height) changed = true;
    root.size = [box.width, box.height];
  }
  if (!changed) return;
  cancelAnimationFrame(redrawing);
  redrawing = requestAnimationFrame(() => { if (state.current) renderDrawing(); });
});

function panel(id, title) {
  let box = document.getElementById(id);
  if (!box) {
    box = el("div", { class: "panel", id });
    box.append(el("h3", {}, title), svg("svg", { preserveAspectRatio: "none" }), el("div", { class: "legend" }));
    document.getElementById("panels").append(box);
    resized.observe(box.querySelector("svg"));
  }
  return box;
}

// one drawing panel: axes, surfaces, curves and points, the pose; the frame kept for the animation
function drawPanel(box, id, group, ghost, mechanism, ghostMech) {
  const root = box.querySelector("svg");
  const values = (state.current && state.current.values) || {};
  const surfaces = surfacesOf(id, group, values);
  const f = frameOf(root, extent([group, ghost, mechanism, ghostMech && ghostMech.frames.length ? ghostMech : null],
                                 surfaces), true);
  root.setAttribute("viewBox", `0 0 ${f.width} ${f.height}`);
  root.replaceChildren();
  root.frame = f;
  drawAxes(root, f, "x, mm", "y, mm");
  const clip = `clip-${id}`;
  const defs = svg("defs");
  const clipPath = svg("clipPath", { id: clip });
  clipPath.append(svg("rect", { x: f.left, y: f.top, width: f.right - f.left, height: f.bottom - f.top }));
  defs.append(clipPath);
  const data = svg("g", { class: "data", "clip-path": `url(#${clip})` });
  root.append(defs, data);
  drawSurfaces(data, f, surfaces);
  if (ghost) drawGroup(data, ghost, f, true);
  drawGroup(data, group, f, false);
  if (ghostMech && ghostMech.frames.length) {
    const ghostPoses = svg("g", { class: "ghost-poses" });
    data.append(ghostPoses);
    drawPose(ghostPoses, ghostMech, state.frame, f, true);
  }
  if (mechanism) {
    const poses = svg("g", { class: "poses" });
    data.append(poses);
    drawPose(poses, mechanism, state.frame, f, false);
  }
  drawScaleBar(root, f);
  const legend = box.querySelector(".legend");
  legend.replaceChildren();
  (group.lines || []).forEach((l, i) => {
    const s = el("span");
    const swatch = el("i");
    swatch.style.background = COLOURS[i % COLOURS.length];
    s.append(swatch, document.createTextNode(l.name));
    legend.append(s);
  });
  for (const s of surfaces) {
    const item = el("span");
    const swatch = el("i");
    swatch.style.background = s.colour;
    item.append(swatch, document.createTextNode(s.name));
    legend.append(item);
  }
  if (ghost) legend.append(el("span", {}, "grey dashed: baseline (the spec's given design)"));
}

function renderDrawing() {
  const data = state.current;
  const comparing = document.getElementById("compare").checked && state.baseline && state.baseline.drawing;
  document.body.classList.toggle("comparing", Boolean(comparing));
  if (!data || !data.drawing) {           // not evaluated at these values: draw nothing rather than a stale design
    document.getElementById("panels").replaceChildren();
    return;
  }
  const d = data.drawing;
  const b = comparing ? state.baseline.drawing : null;
  const mech = d.mechanism && d.mechanism.frames.length ? d.mechanism : null;
  const sections = [["panel-main", d.ground ? "machine frame (mm)" : "mechanism and curves (mm)", d.main, b && b.main, mech, b && b.mechanism]];
  if (d.ground) sections.push(["panel-ground", "ground frame (mm)", d.ground, b && b.ground, null, null]);
  // a kind whose check draws no curve, point or pose (combing_chain: its answer is a chart) gets no empty panel
  const drawn = (g) => g && ((g.lines || []).length || (g.points || []).length);
  for (let i = sections.length - 1; i >= 0; i--) {
    const [, , group, ghost, mechanism] = sections[i];
    if (!drawn(group) && !drawn(ghost) && !mechanism) sections.splice(i, 1);
  }
  for (const id of ["panel-main", "panel-ground"]) {
    if (!sections.some((s) => s[0] === id) && document.getElementById(id)) document.getElementById(id).remove();
  }
  for (const [id, title, group, ghost, mechanism, ghostMech] of sections) {
    drawPanel(panel(id, title), id, group, ghost, mechanism, ghostMech);
  }
  renderCharts(d.charts || [], b ? b.charts : null);
}

function renderCharts(charts, ghosts) {
  const box = document.getElementById("panels");
  box.querySelectorAll(".chart").forEach((node) => { if (Number(node.dataset.index) >= charts.length) node.remove(); });
  charts.forEach((chart, i) => {
    let panelBox = document.getElementById(`chart-${i}`);
    if (!panelBox) {
      panelBox = el("div", { class: "panel chart", id: `chart-${i}`, "data-index": String(i) });
      panelBox.append(el("h3"), svg("svg", { preserveAspectRatio: "none" }), el("div", { class: "legend" }));
      box.append(panelBox);
      resized.observe(panelBox.querySelector("svg"));
    }
    const unit = chart.unit || "deg";       // the facts' angle charts are in deg; the dynamics say their unit
    // one curve: its own name says what is plotted (a cam's "follower" table holds only its pressure angle here)
    const what = chart.series.length === 1 ? `${chart.series[0].name} (${unit})` : unit;
    panelBox.querySelector("h3").textContent = `${chart.name}: ${what} over ${chart.x_name}`;
    const ghost = ghosts && ghosts[i] && ghosts[i].name === chart.name ? ghosts[i] : null;
    const all = [chart, ghost].filter(Boolean);
    const xs = all.flatMap((c) => c.x).filter((v) => v !== null);
    const ys = all.flatMap((c) => c.series.flatMap((s) => s.y)).filter((v) => v !== null);
    const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
    const h = Math.max(y1 - y0, 1e-9);
    const root = panelBox.querySelector("svg");
    const f = frameOf(root, [x0, y0 - 0.05 * h, x1, y1 + 0.05 * h], false);
    root.setAttribute("viewBox", `0 0 ${f.width} ${f.height}`);
    root.replaceChildren();
    drawAxes(root, f, `${chart.x_name}`, unit);
    for (const [c, grey] of [[ghost, true], [chart, false]]) {
      if (!c) continue;
      c.series.forEach((s, k) => root.append(svg("path", { d: pathOf(c.x, s.y, f), fill: "none", "data-series": s.name,
        stroke: grey ? "#888" : COLOURS[k % COLOURS.length], "stroke-width": 1.8, "stroke-dasharray": grey ? "5 4" : "",
        opacity: grey ? "0.5" : "1" })));
    }
    const legend = panelBox.querySelector(".legend");
    legend.replaceChildren(el("span", {}, `${chart.x_name} ${fmt(x0)} … ${fmt(x1)};`));
    chart.series.forEach((s, k) => {
      const item = el("span");
      const swatch = el("i");
      swatch.style.background = COLOURS[k % COLOURS.length];
      const finite = s.y.filter((v) => v !== null);
      item.append(swatch, document.createTextNode(`${s.name} ${fmt(Math.min(...finite))} … ${fmt(Math.max(...finite))}`));
      legend.append(item);
    });
  });
}

function tick() {
  const data = state.current;
  if (!data || !data.drawing || !data.drawing.mechanism.frames.length) return;
  state.frame += 1;
  const root = document.querySelector("#panel-main svg");
  const poses = root && root.querySelector("g.poses");
  if (!poses || !root.frame) return;
  poses.replaceChildren();
  drawPose(poses, data.drawing.mechanism, state.frame, root.frame, false);
  const ghostPoses = root.querySelector("g.ghost-poses");      // the baseline moves in step when compared
  if (ghostPoses && state.baseline && state.baseline.drawing) {
    ghostPoses.replaceChildren();
    drawPose(ghostPoses, state.baseline.drawing.mechanism, state.frame, root.frame, true);
  }
}

function animate() {
  clearInterval(state.timer);
  state.timer = document.getElementById("animate").checked ? setInterval(tick, 80) : null;
}

// ---- buttons --------------------------------------------------------------------------------------------
async function save() {
  try {
    const data = await api("/api/save", { values: freeValues() });
    document.getElementById("saved").textContent = `saved ${data.file} in ${data.folder}`;
    document.body.dataset.saved = data.file;
  } catch (err) { showError(String(err.message || err)); }
}

function reset() {
  for (const v of state.info.variables) setValue(v.name, state.given[v.name]);
  request("fine");
}

function showSolve(s) {
  const running = s.state === "running" || s.state === "cancelling";
  document.getElementById("solve").disabled = running;
  document.getElementById("cancel").disabled = !running;
  const bar = document.getElementById("progress");
  bar.max = Math.max(1, s.total || 1);
  bar.value = s.done || 0;
  let text = s.state === "idle" ? "no solve yet" : `${s.run}: ${s.state}, ${s.done || 0}/${s.total || "?"} starts`;
  if (!running && s.exit) text += `; ${s.exit}`;
  if (s.status) text += `; status ${s.status}` + (s.objective ? `, ${s.objective.name} = ${fmt(s.objective.value)}` : "");
  if (s.folder) text += `; run written to ${s.folder}/`;
  document.getElementById("solve-state").textContent = text;
  document.getElementById("solve-lines").textContent = (s.lines || []).join("\n");
  document.body.dataset.solve = s.state;
}

// the sliders take a solve's design only when this page started it and it finished; an earlier run (found on
// load, or cancelled) is only reported in the solve line: the page opens on the spec's values
function poll() {
  clearTimeout(state.polling);
  api("/api/solve").then((s) => {
    showSolve(s);
    if (s.state === "running" || s.state === "cancelling") { state.polling = setTimeout(poll, 300); return; }
    const adopt = state.solving && s.state === "finished";
    state.solving = false;
    if (!adopt && s.design) {
      document.getElementById("solve-state").textContent += "; its design is not loaded into the sliders";
    }
    if (adopt && s.design) {
      // IPOPT may end a hair outside a bound (its bound relaxation, ~1e-8 relative); a spec's start value must lie
      // within its bounds, so such a value is put on the bound, and the page says by how much
      const clamped = [];
      for (const v of state.info.variables) {
        const x = s.design[v.name];
        if (!v.free || typeof x !== "number") continue;
        const inside = Math.min(v.bounds[1], Math.max(v.bounds[0], x));
        if (inside !== x) clamped.push(`${v.name} by ${fmt(Math.abs(inside - x))} ${v.unit}`);
        setValue(v.name, inside);
      }
      if (clamped.length) {
        document.getElementById("solve-state").textContent += `; put on its bound: ${clamped.join(", ")}`;
      }
      request("fine");
    }
  }).catch((err) => showError(String(err.message || err)));
}

async function solve() {
  try {
    const box = document.getElementById("starts");
    // sent as typed when it is no number (the server names the field and the text), never as Number("") = 0
    const starts = Number.isFinite(typedNumber(box)) ? typedNumber(box) : (box.value.trim() || "(empty)");
    showSolve(await api("/api/solve", { values: freeValues(), starts }));
    state.solving = true;
    poll();
  } catch (err) { showError(String(err.message || err)); }
}

async function cancel() {
  try { showSolve(await api("/api/solve/cancel", {})); poll(); } catch (err) { showError(String(err.message || err)); }
}

async function start() {
  state.info = await api("/api/session");
  document.getElementById("title").textContent = `— ${state.info.name} (${state.info.kind}, ${state.info.spec})`;
  document.getElementById("grids").textContent =
    `While a slider moves the rules are evaluated on the coarse grid (${state.info.grids.coarse}); ` +
    `on release, on the fine grid (${state.info.grids.fine}) — the grid agrisynth check uses. ` +
    `Files are written to ${state.info.folder}.`;
  for (const v of state.info.variables) { state.values[v.name] = v.value; state.given[v.name] = v.value; }
  document.getElementById("starts").value = state.info.starts;
  const solvable = state.info.solves && state.info.variables.some((v) => v.free);
  document.getElementById("solve").disabled = !solvable;
  if (!solvable) document.getElementById("solve-state").textContent = "nothing free to solve for in this spec";
  buildSliders();
  state.baseline = await api("/api/evaluate", { values: freeValues(), grid: "fine" });
  render(state.baseline, 0);
  document.body.dataset.busy = "0";
  document.getElementById("save").addEventListener("click", save);
  document.getElementById("reset").addEventListener("click", reset);
  document.getElementById("solve").addEventListener("click", solve);
  document.getElementById("cancel").addEventListener("click", cancel);
  document.getElementById("compare").addEventListener("change", () => {
    if (state.current) renderTable(state.current);
    renderDrawing();
  });
  document.getElementById("animate").addEventListener("change", animate);
  animate();
  if (solvable) poll();
  document.body.dataset.ready = "1";
}

start().catch((err) => showError(String(err.message || err)));
