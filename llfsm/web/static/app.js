// llfsm view: live over one WebSocket; commands, publishing and service calls as JSON POSTs.
// Everything user-provided is set with textContent; the only markup inserted is the SVG the
// server generated (diagrams, turtle world), parsed as SVG, never as HTML.  The server escapes
// every text of a peer's in that SVG (llfsm view shows what any DDS peer publishes); the page
// also keeps only the elements a drawing is made of and drops event handlers and links, so a
// mistake there still cannot put a peer's element or script into the page.
"use strict";

const cards = new Map(); // machine name -> {el, states: Map(state -> <g>), current}
let lastWorld = null;
const token = new URLSearchParams(location.search).get("token");

const SVG_ELEMENTS = new Set(["svg", "defs", "marker", "path", "g", "title", "rect", "text", "circle", "polygon"]);

function svgNode(text) {
  const doc = new DOMParser().parseFromString(text, "image/svg+xml");
  const root = doc.documentElement;
  if (root.nodeName !== "svg" || doc.getElementsByTagName("parsererror").length) {
    return document.createTextNode("(cannot draw)");
  }
  for (const e of [...root.querySelectorAll("*")]) {
    if (!SVG_ELEMENTS.has(e.localName)) { e.remove(); continue; }
    for (const a of [...e.attributes]) {
      if (a.name.startsWith("on") || a.localName === "href" || a.localName === "style") e.removeAttribute(a.name);
    }
  }
  return document.importNode(root, true);
}

function el(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined && text !== null) e.textContent = text;
  if (cls) e.className = cls;
  return e;
}

async function post(path, body) {
  const headers = { "Content-Type": "application/json" };
  if (token) headers["X-LLFSM-Token"] = token;
  try {
    const r = await fetch(path, { method: "POST", headers, body: JSON.stringify(body), credentials: "same-origin" });
    return await r.json();
  } catch (e) {
    return { success: false, message: String(e) };
  }
}

function show(output, result) {
  output.dataset.ok = String(!!result.success);
  output.textContent = result.message + (result.yaml ? "\n" + result.yaml : "");
}

function buildMachines(machines) {
  const box = document.getElementById("machines");
  box.replaceChildren();
  cards.clear();
  const tpl = document.getElementById("machine-card");
  for (const m of machines) {
    const el_ = tpl.content.firstElementChild.cloneNode(true);
    el_.dataset.machine = m.name;
    el_.querySelector(".machine-name").textContent = m.name;
    el_.querySelector(".description").textContent = m.description || "";
    el_.querySelector(".inputs").textContent = (m.inputs || []).length ? "inputs: " + m.inputs.join("; ") : "";
    el_.querySelector(".diagram-box").append(svgNode(m.svg));
    const states = new Map();
    for (const g of el_.querySelectorAll(".state")) states.set(g.dataset.state, g);
    for (const b of el_.querySelectorAll("button[data-command]")) {
      b.addEventListener("click", async () => {
        const out = el_.querySelector(".command-result");
        out.textContent = "…";
        show(out, await post("/api/command", { machine: m.name, command: b.dataset.command }));
      });
    }
    box.append(el_);
    cards.set(m.name, { el: el_, states, current: null });
  }
}

function updateMachine(m) {
  const card = cards.get(m.name);
  if (!card) return;
  if (card.current !== m.state) {
    for (const [name, g] of card.states) g.setAttribute("aria-current", name === m.state ? "true" : "false");
    card.current = m.state;
  }
  card.el.dataset.status = m.status;
  const badge = card.el.querySelector(".status");
  badge.textContent = m.status + (m.pending ? ` (${m.pending} pending)` : "");
  badge.dataset.status = m.status;
  card.el.querySelector(".current").textContent = `${m.state} since ${m.since.toFixed(3)} s`;
  const list = card.el.querySelector(".transitions");
  const items = m.transitions.map((t) => el("li", `${t.t.toFixed(3)} s  ${t.from} → ${t.to}`));
  list.replaceChildren(...items);
}

function updateTopics(topics) {
  const body = document.querySelector("#topics tbody");
  const rows = [];
  const names = [];
  for (const t of topics) {
    names.push(t.name);
    const tr = el("tr");
    tr.dataset.topic = t.name;
    tr.append(el("td", t.name), el("td", t.type),
      el("td", t.count === null ? "—" : String(t.count), "num count"),
      el("td", t.rate === null ? "—" : `${t.rate.toFixed(1)} Hz`, "num rate"));
    rows.push(tr);
    if (t.count === null) { tr.className = "last"; tr.title = t.last; continue; } // /llfsm/...: the diagrams show it
    const last = el("tr", null, "last");
    last.dataset.topic = t.name;
    const td = el("td");
    td.colSpan = 4;
    td.append(el("pre", t.last || "", "yaml"));
    last.append(td);
    rows.push(last);
  }
  body.replaceChildren(...rows);
  fillList("topic-names", names);
  fillList("msg-types", [...new Set(topics.map((t) => t.type))]);
}

function fillList(id, names) {
  const list = document.getElementById(id);
  const key = names.join("\n");
  if (list.dataset.key === key) return;
  list.dataset.key = key;
  list.replaceChildren(...names.map((n) => { const o = el("option"); o.value = n; return o; }));
}

function snapshot(s) {
  document.getElementById("run-time").textContent =
    `run time ${s.t.toFixed(3)} s (${s.clock} clock)` + (s.ended ? " — the run has ended" : "");
  for (const m of s.machines) updateMachine(m);
  updateTopics(s.topics);
  fillList("service-names", s.services.map((x) => x.name));
  const panel = document.getElementById("world-panel");
  if (s.world) {
    panel.hidden = false;
    if (s.world !== lastWorld) {
      lastWorld = s.world;
      document.getElementById("world").replaceChildren(svgNode(s.world));
    }
  }
  if (s.ended) setConnection("ended");
}

function setConnection(status) {
  const c = document.getElementById("connection");
  c.textContent = status;
  c.dataset.status = status;
}

function connect() {
  const url = `ws://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : "");
  const ws = new WebSocket(url);
  ws.onopen = () => setConnection("live");
  ws.onclose = () => { if (document.getElementById("connection").dataset.status !== "ended") setConnection("closed"); };
  ws.onmessage = (ev) => {
    const msg = JSON.parse(ev.data);
    if (msg.type === "hello") {
      buildMachines(msg.machines);
      snapshot(msg.snapshot);
    } else if (msg.type === "snapshot") {
      snapshot(msg);
    }
  };
}

function formHandler(id, path, outputId) {
  document.getElementById(id).addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const f = ev.target;
    const body = {};
    for (const [k, v] of new FormData(f)) body[k] = String(v);
    const out = document.getElementById(outputId);
    out.textContent = "…";
    show(out, await post(path, body));
  });
}

formHandler("publish-form", "/api/publish", "publish-result");
formHandler("call-form", "/api/call", "call-result");
connect();
