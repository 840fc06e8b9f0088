// rll-bt view: follows the server's state over server-sent events (/events) and draws it.
// The server sends the whole state first ({reset: true, set, append}), then what changed:
// "set" replaces keys ("robots/2" is state.robots["2"]), "append" extends the lists
// (score, events, paths per robot).  No build step: plain ES2020 in the browser.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const ROBOT_COLOURS = ["#e6550d", "#3182bd", "#31a354", "#756bb1", "#636363"];
const COLOURS = {
  RED: "#d62728", BLACK: "#222", SILVER: "#c0c0c0", BLUE: "#1f77b4", GREEN: "#2ca02c",
  ORANGE: "#ff7f0e", YELLOW: "#f2d600", GREY: "#888", CLEAR: "#fff",
};

let S = null;                  // the state as the server sent it
let dirty = false;
let updates = 0;
let fieldKey = null;           // the field drawn (redrawn when the profile changes)

window.rllView = { get state() { return S; }, get updates() { return updates; } };

function el(tag, attrs = {}, parent = null, ns = SVG) {
  const e = ns ? document.createElementNS(ns, tag) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function robotColour(n) { return ROBOT_COLOURS[(Number(n) - 1) % ROBOT_COLOURS.length]; }
function colourOf(name) {
  if (!name) return "#fff";
  const key = String(name).split("_").pop();
  return COLOURS[key] || "#ccc";
}
function fmt(x, digits = 1) { return x === null || x === undefined ? "–" : Number(x).toFixed(digits); }

// -- state ------------------------------------------------------------------------------------
function apply(d) {
  if (d.reset || S === null) S = { paths: {}, score: [], events: [] };
  for (const [key, value] of Object.entries(d.set || {})) {
    const parts = key.split("/");
    let o = S;
    for (const p of parts.slice(0, -1)) o = (o[p] = o[p] || {});
    o[parts[parts.length - 1]] = value;
  }
  const a = d.append || {};
  for (const key of ["score", "events"]) {
    if (!a[key]) continue;
    if (d.reset) S[key] = a[key]; else S[key].push(...a[key]);
  }
  if (a.paths) {
    if (d.reset) S.paths = a.paths;
    else for (const [r, pts] of Object.entries(a.paths)) (S.paths[r] = S.paths[r] || []).push(...pts);
  }
  updates += 1;
  dirty = true;
}

function connect() {
  const link = document.getElementById("link");
  const es = new EventSource("/events");
  es.onopen = () => { link.className = "link up"; };
  es.onmessage = (ev) => apply(JSON.parse(ev.data));
  es.onerror = () => { link.className = "link down"; };   // the browser reconnects by itself
}

// -- the field --------------------------------------------------------------------------------
function drawField(svg, f) {
  svg.replaceChildren();
  const pad = 0.9;            // robots start outside the field, in the insertion area
  svg.setAttribute("viewBox", `${f.x_min - pad} ${-(f.y_max + pad)} ${f.x_max - f.x_min + 2 * pad} ${f.y_max - f.y_min + 2 * pad}`);
  el("rect", { x: f.x_min, y: -f.y_max, width: f.x_max - f.x_min, height: f.y_max - f.y_min,
               fill: "#f4f4f4", stroke: "#999", "stroke-width": 0.03 }, svg);
  const zones = el("g", { id: "zones" }, svg);
  for (const z of f.zones) {
    el("rect", { class: `zone ${z.team}`, x: z.x_min, y: -z.y_max, width: z.x_max - z.x_min,
                 height: z.y_max - z.y_min }, zones);
    const t = el("text", { class: "zone-name", x: z.x_min + 0.05, y: -z.y_max + 0.2 }, zones);
    t.textContent = z.name;
  }
  el("g", { id: "paths" }, svg);
  el("g", { id: "stations" }, svg);
  el("g", { id: "robots" }, svg);
}

function drawStations(svg, stations, mps) {
  const g = svg.querySelector("#stations");
  g.replaceChildren();
  for (const s of Object.values(stations || {})) {
    if (!s.pose) continue;
    const [x, y, th] = s.pose;
    const st = el("g", { class: `station ${s.team || ""}`, id: `station-${s.name}`, "data-state": s.state || "",
                         transform: `translate(${x} ${-y})` }, g);
    el("rect", { x: -mps.depth / 2, y: -mps.width / 2, width: mps.depth, height: mps.width,
                 transform: `rotate(${-th * 180 / Math.PI})` }, st);
    const label = el("text", { class: "label", x: 0, y: -0.4, "text-anchor": "middle" }, st);
    label.textContent = s.name;
    const state = el("text", { class: "state", x: 0, y: 0.5, "text-anchor": "middle" }, st);
    state.textContent = s.state || "";
  }
}

function drawRobots(svg, robots, paths) {
  const pg = svg.querySelector("#paths");
  pg.replaceChildren();
  for (const [n, pts] of Object.entries(paths || {})) {
    if (pts.length < 2) continue;
    el("polyline", { class: "path", id: `path-${n}`, stroke: robotColour(n),
                     points: pts.map(p => `${p[1]},${-p[2]}`).join(" ") }, pg);
  }
  const rg = svg.querySelector("#robots");
  rg.replaceChildren();
  for (const [n, r] of Object.entries(robots || {})) {
    const pose = r.true_pose || r.pose;
    if (!pose) continue;
    const c = robotColour(n);
    if (r.true_pose && r.pose) {
      el("circle", { class: "estimate", id: `estimate-${n}`, cx: r.pose[0], cy: -r.pose[1], r: 0.28, stroke: c }, rg);
    }
    const [x, y, th] = pose;
    const g = el("g", { class: "robot", id: `robot-${n}`, "data-x": x, "data-y": y,
                        transform: `translate(${x} ${-y}) rotate(${-th * 180 / Math.PI})` }, rg);
    el("circle", { class: "body", r: 0.23, fill: c }, g);
    el("line", { class: "heading", x1: 0, y1: 0, x2: 0.3, y2: 0 }, g);
    const t = el("text", { x: -0.07, y: 0.08, transform: `rotate(${th * 180 / Math.PI})` }, g);
    t.textContent = n;
  }
}

// -- score, orders, events -------------------------------------------------------------------------
function drawScore(svg, score) {
  svg.replaceChildren();
  const W = 400, H = 140, L = 30, B = 18;
  el("line", { class: "axis", x1: L, y1: H - B, x2: W, y2: H - B }, svg);
  el("line", { class: "axis", x1: L, y1: 0, x2: L, y2: H - B }, svg);
  if (!score.length) return;
  const t0 = score[0][0], t1 = Math.max(score[score.length - 1][0], t0 + 1);
  const pmax = Math.max(10, ...score.map(s => s[1]));
  const X = t => L + (W - L) * (t - t0) / (t1 - t0);
  const Y = p => (H - B) - (H - B - 5) * p / pmax;
  let pts = [];
  let prev = null;
  for (const s of score) {
    if (prev !== null) pts.push(`${X(s[0])},${Y(prev)}`);      // a step: points change at once
    pts.push(`${X(s[0])},${Y(s[1])}`);
    prev = s[1];
  }
  el("polyline", { class: "line", points: pts.join(" ") }, svg);
  const top = el("text", { x: 2, y: 12 }, svg); top.textContent = pmax;
  const zero = el("text", { x: 2, y: H - B }, svg); zero.textContent = "0";
  const end = el("text", { x: W - 4, y: H - 4, "text-anchor": "end" }, svg);
  end.textContent = `${fmt(t1 - t0, 0)} s`;
}

function drawOrders(tbody, orders, game) {
  tbody.replaceChildren();
  const colour = (game && game.color) || "CYAN";
  const production = game && game.phase === "PRODUCTION";
  const gt = game ? game.game_time : 0;
  const tmax = Math.max(60, ...orders.map(o => o.end || 0));
  for (const o of orders) {
    const done = o.delivered[colour] || 0;
    const tr = el("tr", { "data-order": o.id }, tbody, null);
    if (done >= o.requested) tr.className = "done";
    else if (production && o.begin <= gt && gt <= o.end) tr.className = "active";
    el("td", {}, tr, null).textContent = `${o.id} ${o.complexity}${o.competitive ? " ⚔" : ""}`;
    const prod = el("td", {}, tr, null);
    for (const c of [o.base, ...o.rings, o.cap]) {
      const chip = el("span", { class: "chip", title: c || "" }, prod, null);
      chip.style.background = colourOf(c);
    }
    el("td", {}, tr, null).textContent = `${done}/${o.requested}`;
    const w = el("td", {}, tr, null);
    const bar = el("div", { class: "window", title: `${o.begin}–${o.end} s` }, w, null);
    const span = el("div", { class: "span" }, bar, null);
    span.style.left = `${100 * o.begin / tmax}%`;
    span.style.width = `${100 * (o.end - o.begin) / tmax}%`;
    if (production) {
      const now = el("div", { class: "now" }, bar, null);
      now.style.left = `${Math.min(100, 100 * gt / tmax)}%`;
    }
    el("span", { class: "muted" }, w, null).textContent = ` ${o.begin}–${o.end}`;
  }
}

function drawEvents(ul, events) {
  ul.replaceChildren();
  for (const e of events.slice(-12).reverse()) {
    const extra = Object.entries(e).filter(([k]) => k !== "t" && k !== "what").map(([k, v]) => `${k} ${v}`).join(", ");
    el("li", {}, ul, null).textContent = `${fmt(e.t)} s: ${e.what}${extra ? " (" + extra + ")" : ""}`;
  }
}

// -- trees ----------------------------------------------------------------------------------------
function drawTrees(div, robots) {
  const seen = new Set();
  for (const [n, r] of Object.entries(robots || {})) {
    seen.add(n);
    let panel = div.querySelector(`#tree-${n}`);
    if (!panel) {
      panel = el("div", { class: "tree", id: `tree-${n}` }, div, null);
      el("h3", {}, panel, null);
      el("div", { class: "nodes" }, panel, null);
    }
    const tree = r.tree;
    const h = panel.querySelector("h3");
    h.style.color = robotColour(n);
    if (!tree) {
      h.textContent = `robot ${n}: ${r.task ? r.task.kind : "no task"}`;
      panel.querySelector(".nodes").replaceChildren();
      continue;
    }
    const outcome = tree.outcome ? ` → ${tree.outcome.status}` : (tree.status ? ` (${tree.status}, tick ${tree.tick})` : "");
    h.textContent = `robot ${n}: ${tree.kind} #${tree.task_id}${outcome}`;
    const nodes = panel.querySelector(".nodes");
    if (nodes.dataset.task !== String(tree.task_id) || nodes.childElementCount !== tree.nodes.length) {
      nodes.replaceChildren();
      nodes.dataset.task = String(tree.task_id);
      for (const node of tree.nodes) {
        const d = el("div", { class: "node", "data-id": node.id }, nodes, null);
        d.style.paddingLeft = `${node.depth * 1.1}em`;
        d.textContent = node.name;
        el("span", { class: "type" }, d, null).textContent = node.type;
      }
    }
    const running = new Set(tree.running || []);
    const status = new Map((tree.visited || []).map(([id, st]) => [id, st]));
    for (const d of nodes.children) {
      const id = Number(d.dataset.id);
      d.className = "node" + (running.has(id) ? " running" : "") + (status.has(id) ? " " + status.get(id) : "");
    }
  }
  for (const panel of [...div.children]) if (!seen.has(panel.id.slice(5))) panel.remove();
}

// -- header and playback --------------------------------------------------------------------------
function drawHeader(s) {
  const m = s.meta || {};
  const src = m.source === "replay" ? `replay of ${m.file}` : m.source === "foxglove" ? `live from ${m.name || m.url}` : `live: ${m.name || "game"}`;
  document.getElementById("source").textContent = `${src} · ${(s.field || {}).profile || ""}`;
  const g = s.game || {};
  const phase = document.getElementById("phase");
  phase.textContent = g.phase ? `${g.phase}${g.state && g.state !== "RUNNING" ? " " + g.state : ""}` : "–";
  document.getElementById("game-time").textContent = fmt(g.game_time);
  const colour = g.color || m.color || "CYAN";
  document.getElementById("score").textContent = g.points ? g.points[colour] : "–";
  document.getElementById("clock").textContent = fmt(s.t);
  const pb = s.playback;
  const box = document.getElementById("playback");
  box.hidden = !pb;
  if (pb) {
    document.getElementById("play").textContent = pb.playing ? "❚❚" : "▶";
    const seek = document.getElementById("seek");
    seek.min = pb.start; seek.max = pb.end;
    if (document.activeElement !== seek) seek.value = pb.t;
    const speed = document.getElementById("speed");
    if (![...speed.options].some(o => Number(o.value) === pb.speed)) {
      el("option", { value: String(pb.speed) }, speed, null).textContent = `${pb.speed}×`;
    }
    if (document.activeElement !== speed) speed.value = [...speed.options].find(o => Number(o.value) === pb.speed).value;
  }
  const res = s.result;
  document.getElementById("result").textContent = res ?
    `game over after ${fmt(res.sim_time)} s: ${res.finished ? "finished" : "not finished"}, ` +
    `points ${JSON.stringify(res.points)}, ${res.collisions} collisions, ${res.messages} messages` : "";
}

function control(cmd) {
  return fetch("/control", { method: "POST", headers: { "Content-Type": "application/json" },
                              body: JSON.stringify(cmd) });
}

function wireControls() {
  document.getElementById("play").onclick = () =>
    control({ op: S && S.playback && S.playback.playing ? "pause" : "play" });
  const seek = document.getElementById("seek");
  seek.onchange = () => control({ op: "seek", t: Number(seek.value) });
  const speed = document.getElementById("speed");
  speed.onchange = () => control({ op: "speed", speed: Number(speed.value) });
}

function legend(robots) {
  const div = document.getElementById("legend");
  const n = Object.keys(robots || {}).join(",");
  if (div.dataset.robots === n) return;
  div.dataset.robots = n;
  div.replaceChildren();
  for (const r of Object.keys(robots || {})) {
    const s = el("span", {}, div, null);
    const dot = el("span", { class: "dot" }, s, null);
    dot.style.background = robotColour(r);
    s.append(`robot ${r}`);
  }
  el("span", { class: "muted" }, div, null).textContent = "filled: true pose · dashed ring: the robot's estimate";
}

function render() {
  if (dirty && S) {
    dirty = false;
    const svg = document.getElementById("field");
    const key = JSON.stringify(S.field);
    if (key !== fieldKey) { drawField(svg, S.field); fieldKey = key; }
    drawStations(svg, S.stations, S.field.mps);
    drawRobots(svg, S.robots, S.paths);
    legend(S.robots);
    drawScore(document.getElementById("score-chart"), S.score || []);
    drawOrders(document.querySelector("#orders tbody"), S.orders || [], S.game);
    drawEvents(document.getElementById("events"), S.events || []);
    drawTrees(document.getElementById("trees"), S.robots);
    drawHeader(S);
  }
}

wireControls();
connect();
setInterval(render, 100);      // a timer, not animation frames: those stop in a hidden tab
