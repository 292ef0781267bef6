// The executive's live view: frames over a WebSocket, drawn as plain SVG (no library, no internet).
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const CHAR = 6.8;  // px a character of the node names takes, about
const $ = (id) => document.getElementById(id);
const KINDS = { Sequence: "\u2192", Selector: "?", Parallel: "\u21c9" };
const NAMES = { R: "RUNNING", S: "SUCCESS", F: "FAILURE", "-": "INVALID" };
const BB_FIRST = ["/mission/", "/vehicle/", "/link/", "/command/", "/heading/", "/rc/", "/runtime/"];  // then the rest, by name

const view = {
  kind: null, tree: null, nodes: [], depth: [], paths: [], elements: [], edges: [],
  blackboard: {}, track: [], plan: null, here: null, token: null, tokenNeeded: false,
};

function el(name, attrs, parent) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

function clip(text, n) { return text.length > n ? text.slice(0, n - 1) + "\u2026" : text; }

// -- the tree: left to right, a column per depth, leaves one under another, each parent beside its children
function buildTree(tree) {
  const svg = $("tree");
  svg.replaceChildren();
  view.tree = tree;
  view.nodes = tree ? tree.nodes : [];
  view.elements = []; view.edges = []; view.depth = [];
  if (!tree) return;
  const children = view.nodes.map(() => []);
  view.paths = [];
  for (const n of view.nodes) {
    view.depth[n.id] = n.parent === null ? 0 : view.depth[n.parent] + 1;
    view.paths[n.id] = n.parent === null ? n.name : `${view.paths[n.parent]}/${n.name}`;
    if (n.parent !== null) children[n.parent].push(n.id);
  }
  const width = n => Math.min(220, Math.max(80, (KINDS[n.type] ? 46 : 34) + CHAR * n.name.length));
  const colWidth = [];
  for (const n of view.nodes) colWidth[view.depth[n.id]] = Math.max(colWidth[view.depth[n.id]] || 0, width(n));
  const colX = [10];
  for (let d = 1; d < colWidth.length; d++) colX[d] = colX[d - 1] + colWidth[d - 1] + 22;
  const H = 36, GAP = 6, pos = [];
  let row = 0;
  const place = (id) => {
    const kids = children[id];
    if (!kids.length) { pos[id] = 10 + row * (H + GAP); row += 1; return; }
    kids.forEach(place);
    pos[id] = (pos[kids[0]] + pos[kids[kids.length - 1]]) / 2;
  };
  place(0);
  const edgeLayer = el("g", {}, svg);
  for (const n of view.nodes) {
    const x = colX[view.depth[n.id]], y = pos[n.id], w = colWidth[view.depth[n.id]];
    if (n.parent !== null) {
      const px = colX[view.depth[n.parent]] + colWidth[view.depth[n.parent]], py = pos[n.parent] + H / 2, cy = y + H / 2;
      view.edges[n.id] = el("path", { class: "edge", d: `M${px},${py} C${px + 18},${py} ${x - 18},${cy} ${x},${cy}` }, edgeLayer);
    }
    const g = el("g", { class: "node", "data-id": n.id, "data-status": "-", transform: `translate(${x},${y})` }, svg);
    const title = el("title", {}, g);
    title.textContent = `${n.name} (${n.type})`;
    el("rect", { width: w, height: H }, g);
    el("circle", { class: "dot", cx: 10, cy: 12, r: 4 }, g);
    const kind = KINDS[n.type];
    const name = el("text", { class: "name", x: kind ? 32 : 20, y: 16 }, g);
    name.textContent = clip(n.name, Math.floor((w - (kind ? 40 : 28)) / CHAR));
    if (kind) { const k = el("text", { class: "kind", x: 18, y: 16 }, g); k.textContent = kind; }
    const fb = el("text", { class: "fb", x: 20, y: 31 }, g);
    view.elements[n.id] = { g, fb, title, width: w };
  }
  view.treeSize = [Math.max(...view.nodes.map(n => colX[view.depth[n.id]] + colWidth[view.depth[n.id]])) + 10, row * (H + GAP) + 14];
  svg.setAttribute("viewBox", `0 0 ${view.treeSize[0]} ${view.treeSize[1]}`);
  fitTree();
}

// the whole tree in its pane's width (scaled down, never up; a tall tree scrolls)
function fitTree() {
  if (!view.treeSize) return;
  const [w, h] = view.treeSize, scale = Math.min(1, ($("tree").parentElement.clientWidth - 4) / w);
  $("tree").setAttribute("width", w * scale);
  $("tree").setAttribute("height", h * scale);
}

function showStatuses(s, f) {
  for (const n of view.nodes) {
    const e = view.elements[n.id];
    if (!e) continue;
    const status = s[n.id] || "-", note = f[n.id] || "";
    e.g.setAttribute("data-status", status);
    e.fb.textContent = clip(note, Math.floor((e.width - 26) / 6));
    e.title.textContent = `${n.name} (${n.type}): ${NAMES[status]}${note ? " \u2014 " + note : ""}`;
    if (view.edges[n.id]) view.edges[n.id].classList.toggle("running", status === "R");
  }
}

// what the mission waits for: the executive's own verdict (executive.tree.waiting: the deepest running node, or the child it retries)
function showWaiting(waiting) {
  let text = "";
  for (const n of view.nodes) view.elements[n.id].g.classList.toggle("waiting", !!waiting && view.paths[n.id] === waiting.path);
  if (waiting) {
    const seconds = waiting.for_s === null || waiting.for_s === undefined ? "" : ` (${Math.round(waiting.for_s)} s)`;
    text = `waiting: ${waiting.node}${seconds}${waiting.feedback ? ": " + waiting.feedback : ""}`;
  }
  $("waiting").textContent = text;
}

// -- the status bar
function showStatus(status, t, tick) {
  const state = $("state");
  $("clock").textContent = `t ${t.toFixed(1)} s \u00b7 tick ${tick}`;
  if (!status) return;
  state.textContent = status.state;
  state.setAttribute("data-state", status.state);
  $("leg").textContent = `${status.leg}/${status.legs}`;
  $("mode").textContent = status.mode || "-";
  $("armed").textContent = status.armed ? "armed" : "disarmed";
  $("link").textContent = status.link_up ? "up" : "DOWN";
  $("battery").textContent = status.battery_pct === null || status.battery_pct === undefined ? "-"
    : `${status.battery_pct}%` + (status.battery_v ? ` ${Number(status.battery_v).toFixed(1)} V` : "");
  const energy = status.energy;  // Wh left above the reserve / to finish and return, +/- 1 sigma; the margin
  $("energy").textContent = energy ? `${energy.has_wh.toFixed(1)} / ${energy.need_wh.toFixed(1)} \u00b1${energy.sigma_wh.toFixed(1)} Wh`
    + ` (margin ${energy.margin_wh.toFixed(1)})` : "-";
  $("reason").textContent = status.reason || "";
}

// -- the blackboard
function showBlackboard(changed) {
  const first = Object.keys(view.blackboard).length === 0;
  Object.assign(view.blackboard, changed || {});
  const filter = $("filter").value.trim().toLowerCase();
  const body = document.querySelector("#bb tbody");
  const rows = [];
  const rank = key => { const i = BB_FIRST.findIndex(p => key.startsWith(p)); return i < 0 ? BB_FIRST.length : i; };
  for (const key of Object.keys(view.blackboard).sort((a, b) => rank(a) - rank(b) || (a < b ? -1 : 1))) {
    if (filter && !key.toLowerCase().includes(filter)) continue;
    const tr = document.createElement("tr");
    if (changed && !first && key in changed) tr.className = "changed";
    const k = document.createElement("td"), v = document.createElement("td");
    k.textContent = key; v.textContent = view.blackboard[key];
    tr.append(k, v);
    rows.push(tr);
  }
  body.replaceChildren(...rows);
}

// -- the plan: route, home, track and vehicle in local metres (x east, y north: drawn with y flipped)
function showPlan() {
  const svg = $("plan");
  svg.replaceChildren();
  const plan = view.plan, pts = [];
  if (plan) { pts.push(...plan.route); if (plan.home) pts.push(plan.home); }
  pts.push(...view.track);
  if (view.here) pts.push(view.here);
  if (!pts.length) return;
  let [x0, x1, y0, y1] = [Infinity, -Infinity, Infinity, -Infinity];
  for (const [e, n] of pts) { x0 = Math.min(x0, e); x1 = Math.max(x1, e); y0 = Math.min(y0, n); y1 = Math.max(y1, n); }
  const span = Math.max(x1 - x0, y1 - y0, 20), m = span * 0.08;
  svg.setAttribute("viewBox", `${x0 - m} ${-y1 - m} ${x1 - x0 + 2 * m} ${y1 - y0 + 2 * m}`);
  const step = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000].find(s => span / s <= 10) || 10000;
  const grid = el("g", {}, svg);
  for (let gx = Math.floor((x0 - m) / step) * step; gx <= x1 + m; gx += step)
    el("line", { class: gx === 0 ? "axis" : "grid", x1: gx, x2: gx, y1: -y1 - m, y2: -y0 + m }, grid);
  for (let gy = Math.floor((y0 - m) / step) * step; gy <= y1 + m; gy += step)
    el("line", { class: gy === 0 ? "axis" : "grid", y1: -gy, y2: -gy, x1: x0 - m, x2: x1 + m }, grid);
  const font = span / 28;
  const label = el("text", { x: x0 - m + font * 0.4, y: -y0 + m - font * 0.4, "font-size": font }, svg);
  label.textContent = `grid ${step} m`;
  if (plan && plan.route.length) {
    el("polyline", { class: "route", points: plan.route.map(([e, n]) => `${e},${-n}`).join(" ") }, svg);
    plan.route.forEach(([e, n], i) => {
      const cls = i < plan.current ? "wp done" : i === plan.current ? "wp current" : "wp";
      el("circle", { class: cls, cx: e, cy: -n, r: span / 90 }, svg);
      const t = el("text", { x: e + span / 70, y: -n - span / 70, "font-size": font }, svg);
      t.textContent = i + 1;
    });
  }
  if (plan && plan.home) {
    const [e, n] = plan.home, s = span / 60;
    el("rect", { class: "home", x: e - s, y: -n - s, width: 2 * s, height: 2 * s }, svg);
  }
  if (view.track.length) el("polyline", { class: "track", points: view.track.map(([e, n]) => `${e},${-n}`).join(" ") }, svg);
  if (view.here) {
    const [e, n] = view.here, s = span / 30, yaw = view.yaw || 0;
    el("polygon", { class: "vehicle", points: `0,${-s} ${s * 0.6},${s * 0.7} 0,${s * 0.3} ${-s * 0.6},${s * 0.7}`,
      transform: `translate(${e},${-n}) rotate(${yaw})` }, svg);
  }
}

// -- frames
function onFrame(msg) {
  if ("tree" in msg && (!view.tree || !msg.tree || msg.tree.id !== view.tree.id)) buildTree(msg.tree);
  showStatuses(msg.s, msg.f);
  showStatus(msg.status, msg.t, msg.tick);
  showWaiting(msg.status && msg.status.state === "RUNNING" ? msg.status.waiting : null);
  showBlackboard(msg.bb);
  view.plan = msg.plan;
  if (msg.track) view.track = msg.track.restart ? msg.track.points : view.track.concat(msg.track.points);
  view.here = msg.here || null;
  view.yaw = msg.status ? msg.status.yaw_deg : null;
  showPlan();
  if (view.kind === "replay") {
    $("slider").value = msg.tick;
    $("tickinfo").textContent = `tick ${msg.tick} at ${msg.t.toFixed(1)} s`;
  }
}

function onHello(msg) {
  view.kind = msg.hello;
  view.tokenNeeded = msg.token_needed;
  const controls = $("controls");
  controls.hidden = !(msg.requests && msg.requests.length);
  if (view.kind === "replay") {
    $("replaybar").hidden = false;
    const slider = $("slider");
    slider.min = msg.first; slider.max = msg.last; slider.value = msg.last;
    document.title = "executive: replay";
  }
}

let socket = null, inFlight = false, wantedTick = null;

function askTick(tick) {
  wantedTick = tick;
  if (!inFlight && socket && socket.readyState === WebSocket.OPEN) {
    inFlight = true;
    socket.send(JSON.stringify({ tick: wantedTick }));
    wantedTick = null;
  }
}

function connect() {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  socket = new WebSocket(`${scheme}://${location.host}/ws`);
  socket.onmessage = (event) => {
    const msg = JSON.parse(event.data);
    if ("hello" in msg) { onHello(msg); return; }
    onFrame(msg);
    inFlight = false;
    if (wantedTick !== null) askTick(wantedTick);
  };
  socket.onclose = () => {
    $("state").textContent = "disconnected";
    $("state").setAttribute("data-state", "");
    setTimeout(connect, 1000);
  };
}

// -- the buttons: through the executive's operator, as `executive ctl`
async function request(op, retried) {
  const headers = { "Content-Type": "application/json" };
  if (view.token) headers["X-Executive-Token"] = view.token;
  $("reply").textContent = `${op}\u2026`;
  let reply;
  try {
    const response = await fetch("/api/request", { method: "POST", headers, body: JSON.stringify({ op }) });
    reply = await response.json();
    if (response.status === 401 && !retried) {
      const token = window.prompt("The executive's token (printed when it started):");
      if (token) { view.token = token.trim(); sessionStorage.setItem("executive-token", view.token); return request(op, true); }
    }
  } catch (error) {
    reply = { ok: false, reason: String(error) };
  }
  $("reply").textContent = `${op}: ${reply.ok ? "done" : "refused"} \u2014 ${reply.reason || ""}`;
}

function start() {
  const params = new URLSearchParams(location.search);
  view.token = params.get("token") || sessionStorage.getItem("executive-token");
  if (params.get("token")) sessionStorage.setItem("executive-token", view.token);
  for (const button of document.querySelectorAll("#controls button")) {
    button.addEventListener("click", () => request(button.dataset.op, false));
  }
  $("filter").addEventListener("input", () => showBlackboard(null));
  window.addEventListener("resize", fitTree);
  $("slider").addEventListener("input", (event) => askTick(Number(event.target.value)));
  connect();
}

start();
