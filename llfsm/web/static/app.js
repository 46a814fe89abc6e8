// llfsm view: live over one WebSocket (protocol 1, docs/view.md "The page's channel": a hello with
// everything, then deltas: only the rows that changed are touched); commands, publishing, service
// calls and parameters as JSON POSTs (docs/view.md).  Everything user-provided is set with textContent; the only markup
// inserted is the SVG the server generated (diagrams, the graph of nodes and topics, the turtle
// world), parsed as SVG, never as HTML.  The server escapes every text of a peer's in that SVG
// (llfsm view shows what any DDS peer publishes); the page also keeps only the elements a drawing
// is made of and drops event handlers and links, so a mistake there still cannot put a peer's
// element or script into the page.
"use strict";

const PROTOCOL = 1; // the channel's version this page speaks (llfsm/web/channel.py)
const cards = new Map(); // machine key -> {el, states: Map(state -> <g>), current, asked}
let ended = false;
// What the channel's messages described so far (a hello replaces it all, a delta changes parts).
const view = { seq: -1, header: {}, machines: new Map(), topics: new Map(), services: new Map() };
const topicRows = new Map(); // topic -> its <tbody> (its row, and the row of its last message)
// How much the page has received and how long applying it took (read by the benchmark).
window.llfsmStats = { messages: 0, bytes: 0, applyMs: 0, maxApplyMs: 0, totalApplyMs: 0 };
const token = new URLSearchParams(location.search).get("token");
const openNodes = new Map(); // node -> the parameter events count its rows were read at
let lastEvents = {}; // node -> parameter events seen (the snapshot's count)
const answers = new Map(); // "node\nparameter" -> the node's last answer to a set from this page

const SVG_ELEMENTS = new Set(["svg", "defs", "marker", "path", "g", "title", "rect", "text", "circle", "polygon",
  "ellipse"]);

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

// A name or type that may wrap only after its slashes or underscores (between words, never
// inside one): `std_msgs/msg/String`, `RotateAbsolute_FeedbackMessage`.
function breakable(tag, text, cls) {
  const e = el(tag, null, cls);
  for (const part of String(text).split(/(?<=[/_])/)) {
    if (e.childNodes.length) e.append(document.createElement("wbr"));
    e.append(part);
  }
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

// -- machines -------------------------------------------------------------------------------------

function buildMachines(machines) {
  const box = document.getElementById("machines");
  box.replaceChildren();
  cards.clear();
  const tpl = document.getElementById("machine-card");
  for (const m of machines) {
    const card = tpl.content.firstElementChild.cloneNode(true);
    card.dataset.machine = m.name;
    card.querySelector(".machine-name").textContent = m.machine || m.name;
    card.querySelector(".description").textContent = m.description || "";
    card.querySelector(".inputs").textContent = (m.inputs || []).length ? "inputs: " + m.inputs.join("; ") : "";
    card.querySelector(".diagram-box").append(svgNode(m.svg));
    const states = new Map();
    for (const g of card.querySelectorAll(".state")) states.set(g.dataset.state, g);
    const entry = { el: card, states, current: null, asked: null, status: null };
    for (const b of card.querySelectorAll("button[data-command]")) {
      b.addEventListener("click", async () => {
        const out = card.querySelector(".command-result");
        out.textContent = "…";
        entry.asked = null;
        const result = await post("/api/command", { machine: m.name, command: b.dataset.command });
        show(out, result);
        // the answer says which delta had been sent when it was given: a later one was sampled after
        if (result.success) entry.asked = { verb: b.dataset.command, seq: result.seq ?? view.seq };
        settleCommands();
      });
    }
    box.append(card);
    cards.set(m.name, entry);
  }
}

function updateMachine(m, s) {
  const card = cards.get(m.name);
  if (!card) return;
  const el_ = card.el;
  if (card.current !== m.state) {
    for (const [name, g] of card.states) g.setAttribute("aria-current", name === m.state ? "true" : "false");
    card.current = m.state;
  }
  const over = s.ended || m.ended;
  const status = over ? "ended" : m.status;
  el_.dataset.status = status;
  const badge = el_.querySelector(".status");
  badge.textContent = over ? (s.ended ? "run ended" : "run gone") : m.status + (m.pending ? ` (${m.pending} pending)` : "");
  badge.dataset.status = status;
  for (const b of el_.querySelectorAll("button[data-command]")) b.disabled = over;
  el_.querySelector(".machine-name").textContent = m.machine || m.name;
  const label = el_.querySelector(".run-label");
  const run = runLabel(m);
  label.hidden = !run;
  label.textContent = run;
  label.title = m.participant ? `the run of DDS participant ${m.participant}` : "";
  el_.querySelector(".state-name").textContent = m.state ?? "(no state yet)";
  const clock = s.source === "view" && !m.run_time ? "view time" : "run time";
  el_.querySelector(".since").textContent = m.state == null ? "" : ` since ${m.since.toFixed(3)} s (${clock})`;
  const twins = el_.querySelector(".twins");
  if (m.runs > 1) {
    twins.hidden = false;
    twins.textContent = `One of ${m.runs} runs of ${m.machine} on this domain (this card: ${run}). They serve ` +
      "the same service names, so a command from any of their cards reaches every one of them.";
  } else {
    twins.hidden = true;
  }
  const list = el_.querySelector(".transitions");
  const items = m.transitions.map((t) => el("li", `${t.t.toFixed(3)} s  ${t.from} → ${t.to}`));
  list.replaceChildren(...items);
  if (over) {
    const out = el_.querySelector(".command-result");
    if (card.asked) { out.textContent = ""; card.asked = null; }
  }
  card.status = status;
}

// A command the run took is "pending until its next ringlet" until the run shows it applied: no
// longer pending in a delta sampled after the answer (one after the delta the answer names).
function settleCommands() {
  for (const [name, card] of cards) {
    const asked = card.asked;
    const m = view.machines.get(name);
    if (!asked || !m || view.seq <= asked.seq || m.pending) continue;
    const out = card.el.querySelector(".command-result");
    out.dataset.ok = "true";
    out.textContent = `${asked.verb} applied: ${m.machine || m.name} is ${card.status} in ${m.state}`;
    card.asked = null;
  }
}

// Which run a card is: the digits the view keys another run by (NAME@xxxxxxxx: its participant's
// GUID after the vendor and host part, the same for every run on one host), for the first too.
function runLabel(m) {
  if (!m.participant) return "";
  const at = m.name.indexOf("@");
  return "run " + (at >= 0 ? m.name.slice(at + 1) : m.participant.slice(8, 16));
}

// -- the monitor's verdicts (snapshot.monitor, docs/view.md) ----------------------------------------

function verdictText(v) {
  const states = Object.entries(v.states).map(([m, st]) => `${m} ${st}`).join(", ");
  if (v.verdict !== "violated") return `${v.property}` + (v.detail ? ` (${v.detail})` : "");
  return `${v.property} at ${v.time.toFixed(3)} s, ringlet ${v.ringlet}` + (v.detail ? ` (${v.detail})` : "") +
    `: ${states}` + (v.variables ? `; ${v.variables}` : "");
}

function updateMonitor(mon) {
  if (!mon || !mon.count) return;
  document.getElementById("monitor-panel").hidden = false;
  const shown = mon.verdicts.length;
  document.getElementById("monitor-count").textContent =
    `${mon.count} verdict${mon.count === 1 ? "" : "s"} on /llfsm/monitor` + (mon.count > shown ? ` (the newest ${shown})` : "");
  const key = JSON.stringify(mon.verdicts);
  const list = document.getElementById("verdicts");
  if (list.dataset.key === key) return;
  list.dataset.key = key;
  list.replaceChildren(...mon.verdicts.map((v) => {
    const li = el("li", verdictText(v));
    li.dataset.verdict = v.verdict.replace("_", " ");
    return li;
  }));
  // a machine a violated property reads is marked, with the property's name
  const marked = new Map();
  for (const v of mon.verdicts) {
    if (v.verdict !== "violated") continue;
    for (const m of v.reads) marked.set(m, [...(marked.get(m) || []), v.property]);
  }
  for (const [name, card] of cards) {
    const names = marked.get(card.el.querySelector(".machine-name").textContent) || marked.get(name);
    const badge = card.el.querySelector(".badge.violation");
    card.el.dataset.violated = String(!!names);
    badge.hidden = !names;
    badge.textContent = names ? `violated: ${names.join("; ")}` : "";
  }
}

// -- topics, services ------------------------------------------------------------------------------

function topicBody(t) {
  const body = el("tbody");
  body.dataset.topic = t.name;
  const tr = el("tr", null, "topic");
  tr.dataset.topic = t.name;
  tr.append(breakable("td", t.name, "name"), breakable("td", t.type, "type"), el("td", "", "num count"),
    el("td", "", "num rate"));
  const last = el("tr", null, "last");
  last.dataset.topic = t.name;
  const td = el("td");
  td.colSpan = 4;
  td.append(el("pre", "", t.machine ? "yaml note" : "yaml"));
  last.append(td);
  body.append(tr, last);
  return body;
}

function fillTopic(body, t) {
  const [tr, last] = body.children;
  if (tr.querySelector(".type").textContent !== t.type) tr.children[1].replaceWith(breakable("td", t.type, "type"));
  tr.querySelector(".count").textContent = t.count === null ? "—" : String(t.count);
  tr.querySelector(".rate").textContent = t.rate === null ? "—" : `${t.rate.toFixed(1)} Hz`;
  tr.className = t.last ? "topic" : "topic bare"; // nothing received yet: no empty row under it
  last.hidden = !t.last;
  const pre = last.querySelector("pre");
  if (pre.textContent !== t.last) pre.textContent = t.last || "";
}

// One topic's rows changed, came or went: only those rows are touched, in name order.
function applyTopics(change) {
  const table = document.getElementById("topics");
  for (const name of change.remove || []) {
    view.topics.delete(name);
    topicRows.get(name)?.remove();
    topicRows.delete(name);
  }
  for (const t of change.upsert || []) {
    view.topics.set(t.name, t);
    let body = topicRows.get(t.name);
    if (!body) {
      body = topicBody(t);
      topicRows.set(t.name, body);
      let next = null; // the first row after it by name (the table stays sorted)
      for (const b of table.tBodies) if (b.dataset.topic > t.name && (!next || b.dataset.topic < next.dataset.topic)) next = b;
      table.insertBefore(body, next);
    }
    fillTopic(body, t);
  }
  const more = (change.total ?? view.topics.size) - view.topics.size;
  const note = document.getElementById("topics-more");
  note.hidden = more <= 0;
  note.textContent = more > 0 ? `${more.toLocaleString("en")} more topics not listed (the table shows at most ` +
    `${view.topics.size})` : "";
  const names = [...view.topics.keys()].sort(); // fillList touches the lists only when they change
  fillList("topic-names", names);
  fillList("msg-types", [...new Set(names.map((n) => view.topics.get(n).type))]);
}

function fillList(id, names) {
  const list = document.getElementById(id);
  const key = names.join("\n");
  if (list.dataset.key === key) return;
  list.dataset.key = key;
  list.replaceChildren(...names.map((n) => { const o = el("option"); o.value = n; return o; }));
}

// -- the graph of nodes and topics, actions, parameters ----------------------------------------

function updateGraph(g) {
  if (!g) return;
  const box = document.getElementById("graph");
  box.replaceChildren(g.svg ? svgNode(g.svg) : el("p", "(the graph could not be drawn)", "hint"));
  for (const n of box.querySelectorAll(".ros-node")) {
    n.addEventListener("click", () => openNode(n.dataset.node));
  }
  const body = document.querySelector("#actions tbody");
  body.replaceChildren(...g.actions.map((a) => {
    const tr = el("tr");
    tr.dataset.action = a.name;
    tr.append(breakable("td", a.name, "name"), breakable("td", a.type || "(type unknown)", "type"),
      el("td", a.servers.join(", ") || "(none)", "server"), el("td", a.clients.join(", ") || "—", "clients"));
    return tr;
  }));
  document.getElementById("no-actions").hidden = g.actions.length > 0;
  const nodes = document.getElementById("nodes");
  const have = new Map([...nodes.children].map((d) => [d.dataset.node, d]));
  const tpl = document.getElementById("node-params");
  const list = [];
  for (const name of g.nodes) {
    let d = have.get(name);
    if (!d) {
      d = tpl.content.firstElementChild.cloneNode(true);
      d.dataset.node = name;
      d.querySelector(".node-name").textContent = name;
      d.addEventListener("toggle", () => {
        if (d.open) readParameters(d); else openNodes.delete(name);
      });
    }
    list.push(d);
  }
  const listed = new Set(g.nodes);
  for (const [name] of have) if (!listed.has(name)) openNodes.delete(name);
  nodes.replaceChildren(...list);
  const more = (g.nodes_total ?? g.nodes.length) - g.nodes.length;
  const note = document.getElementById("nodes-more");
  note.hidden = more <= 0;
  note.textContent = more > 0 ? `${more.toLocaleString("en")} more nodes not listed (at most ${g.nodes.length})` : "";
  const moreActions = (g.actions_total ?? g.actions.length) - g.actions.length;
  const actionsNote = document.getElementById("actions-more");
  actionsNote.hidden = moreActions <= 0;
  actionsNote.textContent = moreActions > 0 ? `${moreActions.toLocaleString("en")} more actions not listed` : "";
}

function openNode(name) {
  const d = [...document.getElementById("nodes").children].find((x) => x.dataset.node === name);
  if (!d) return;
  d.open = true;
  d.scrollIntoView({ block: "nearest" });
}

async function readParameters(d) {
  const name = d.dataset.node;
  const out = d.querySelector(".params-result");
  openNodes.set(name, lastEvents[name] || 0);
  d.dataset.loading = "true";
  const result = await post("/api/parameters", { node: name });
  delete d.dataset.loading;
  if (!result.success) {
    show(out, result);
    return;
  }
  const box = d.querySelector(".params");
  d.querySelector(".count").textContent = `(${result.parameters.length})`;
  const focused = document.activeElement;
  const keep = focused && box.contains(focused) ? focused.closest("form")?.dataset.param : null;
  // what the user is typing survives the rows being read again (a parameter event may come at any time)
  const edits = new Map();
  for (const input of box.querySelectorAll("form.param input")) {
    if (input.value !== input.defaultValue) edits.set(input.closest("form").dataset.param, input.value);
  }
  box.replaceChildren(...result.parameters.map((p) => paramRow(name, p, keep, edits.get(p.name))));
}

function paramRow(node, p, keep, edit) {
  const f = el("form", null, "param");
  f.dataset.param = p.name;
  f.autocomplete = "off";
  const label = el("label");
  label.append(el("span", p.name, "param-name"), el("span", p.type, "param-type"));
  if (p.range) label.append(el("span", `${p.range.from} … ${p.range.to}`, "param-range"));
  const input = el("input");
  input.name = "value";
  input.defaultValue = p.value; // the node's value; the field differs from it while edited
  if (edit !== undefined) input.value = edit;
  input.spellcheck = false;
  input.readOnly = p.read_only;
  if (keep === p.name) queueMicrotask(() => input.focus());
  label.append(input);
  const button = el("button", "Set");
  button.type = "submit";
  button.disabled = p.read_only;
  f.append(label, button);
  if (p.description) f.title = p.description;
  const out = el("output", null, "param-result");
  out.setAttribute("role", "status");
  const key = `${node}\n${p.name}`;
  const said = answers.get(key); // the node's last answer, kept when its rows are read again
  if (said) show(out, said);
  f.append(out);
  f.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    out.textContent = "…";
    const result = await post("/api/parameter", { node, name: p.name, value: input.value });
    answers.set(key, result);
    // the rows may have been read again meanwhile: say it in the form now on the page
    const now = [...document.querySelectorAll("#nodes form.param")]
      .find((x) => x.dataset.param === p.name && x.closest("details").dataset.node === node);
    show(now ? now.querySelector("output") : out, result);
  });
  return f;
}


function parameterEvents(events) {
  lastEvents = events || {};
  for (const [name, seen] of openNodes) {
    if ((lastEvents[name] || 0) !== seen) {
      const d = [...document.getElementById("nodes").children].find((x) => x.dataset.node === name);
      if (d && d.open && !d.dataset.loading) readParameters(d);
    }
  }
}

// -- the whole page: the channel's messages -------------------------------------------------------

// A hello's snapshot or a delta (protocol 1): only what it names changes on the page.
function applyDelta(d) {
  view.seq = d.seq ?? view.seq;
  const header = view.header;
  const wasEnded = !!header.ended;
  if (d.header) Object.assign(header, d.header);
  ended = !!header.ended;
  if (d.header) {
    document.getElementById("run-time").textContent =
      (header.source === "view" ? `view time ${header.t.toFixed(3)} s` :
        `run time ${header.t.toFixed(3)} s (${header.clock} clock)`) + (header.ended ? " — the run has ended" : "");
  }
  if (d.machines) {
    for (const name of d.machines.remove || []) view.machines.delete(name);
    for (const m of d.machines.upsert || []) {
      view.machines.set(m.name, m);
      updateMachine(m, header);
    }
  }
  if (ended !== wasEnded) for (const m of view.machines.values()) updateMachine(m, header);
  if (d.topics) applyTopics(d.topics);
  if (d.services) {
    for (const name of d.services.remove || []) view.services.delete(name);
    for (const x of d.services.upsert || []) view.services.set(x.name, x);
    fillList("service-names", [...view.services.keys()].sort());
  }
  if (d.param_events) parameterEvents({ ...lastEvents, ...d.param_events });
  if ("monitor" in d) updateMonitor(d.monitor);
  // the debugger's page (docs/debug.md): pause, step, breakpoints, variables, history
  const debugLink = document.getElementById("debug-link");
  if (d.debug && debugLink.hidden) {
    debugLink.href = "/debug" + location.search; // the token, if the page has one
    debugLink.hidden = false;
  }
  if ("world" in d && d.world) {
    document.getElementById("world-panel").hidden = false;
    document.getElementById("world").replaceChildren(svgNode(d.world));
  }
  if (ended) {
    setConnection("ended");
    for (const b of document.querySelectorAll("form button")) b.disabled = true;
  }
  settleCommands();
}

// A hello replaces everything the page held.
function reset() {
  view.header = {};
  view.machines.clear();
  view.services.clear();
  for (const body of topicRows.values()) body.remove();
  topicRows.clear();
  view.topics.clear();
  lastEvents = {};
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
  ws.onclose = () => {
    if (ended) return;
    setConnection("closed");
    // the server is gone: nothing on the page can reach the run any more
    for (const b of document.querySelectorAll("button")) b.disabled = true;
  };
  ws.onmessage = (ev) => {
    const started = performance.now();
    const msg = JSON.parse(ev.data);
    if (msg.type === "hello") {
      if (msg.protocol !== PROTOCOL) {
        setConnection(`protocol ${msg.protocol}: this page speaks ${PROTOCOL}; reload it`);
        ws.close();
        return;
      }
      reset();
      buildMachines(msg.machines);
      updateGraph(msg.graph);
      applyDelta(msg.snapshot);
    } else if (msg.type === "delta") {
      applyDelta(msg);
    } else if (msg.type === "graph") {
      updateGraph(msg);
    }
    const stats = window.llfsmStats;
    stats.messages += 1;
    stats.bytes += ev.data.length;
    stats.applyMs = performance.now() - started;
    stats.maxApplyMs = Math.max(stats.maxApplyMs, stats.applyMs);
    stats.totalApplyMs += stats.applyMs;
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
