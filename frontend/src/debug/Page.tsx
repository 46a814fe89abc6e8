// The debugger's page (docs/debug.md, "The page"): `llfsm run --web` and `llfsm view` serve it
// at /debug beside the live view, `llfsm replay` as its page.  Each machine's diagram with its
// current state (or the state at the History slider's record), breakpoints toggled on its
// states and transitions (Alt+click, or B), and its variables; the controls in the header (on
// each machine's card for `llfsm view`, whose machines may belong to different runs).

import { signal } from "@preact/signals";
import { useEffect } from "preact/hooks";
import { connect, type Message, token } from "../api";
import { Diagram } from "../diagram/Diagram";
import { type Live, NO_RUN, reduce } from "../live/live";
import { Controls } from "./Controls";
import { debug, marksOf, readVariables, reduceDebug, said, shownMachine, toggleBreakpoint } from "./store";
import { Variables } from "./Variables";

interface Drawn {
  name: string;
  machine: string;
  svg: string;
}

const drawn = signal<Drawn[]>([]);
const live = signal<Live>(NO_RUN);
const source = signal("");
const connection = signal("connecting");

export function receive(m: Message): void {
  if (m.type === "hello") drawn.value = (m.machines as Drawn[]) ?? [];
  const part = m.type === "hello" ? (m.snapshot as Record<string, unknown> | undefined) : m.type === "delta" ? m : undefined;
  const header = part?.header as Record<string, unknown> | undefined;
  if (header?.source !== undefined) source.value = String(header.source);
  live.value = reduce(live.value, m as Record<string, unknown>);
  reduceDebug(m as Record<string, unknown>);
}

function Card(props: { d: Drawn }) {
  const { d } = props;
  const l = live.value.machines[d.machine];
  const shown = shownMachine(d.name, l?.state ?? null);
  const view = source.value === "view";
  const run = debug.value.runs?.[d.machine];
  const paused = run?.paused ?? false;
  useEffect(() => {
    if (view && paused) void readVariables(d.name); // another process's run: read when it stands
  }, [view, paused, run?.where, d.name]);
  return (
    <section class="card debug-card" aria-label={`machine ${d.name}`}>
      <div class="canvas-bar">
        <h2>{d.name}</h2>
        {view && <Controls machine={d.name} paused={paused} where={run?.where ?? ""} />}
        <span class="live" data-status={l?.status ?? ""}>{shown.state ?? "…"}</span>
      </div>
      <div class="debug-body">
        <Diagram
          machine={d.name}
          svg={d.svg}
          current={shown.state}
          breakpoints={marksOf(d.machine, debug.value.breaks)}
          onToggleBreakpoint={debug.value.replay ? undefined : (sel) => void toggleBreakpoint(d.machine, sel, d.name)}
        />
        <Variables machine={d.name} name={d.name} liveState={l?.state ?? null} />
      </div>
    </section>
  );
}

export function DebugPage() {
  const d = debug.value;
  const s = said.value;
  const home = "/" + (token ? `?token=${encodeURIComponent(token)}` : "");
  return (
    <>
      <header class="top">
        <h1>{d.replay ? "llfsm replay" : "llfsm debug"}</h1>
        {source.value !== "view" && <Controls />}
        {!d.replay && <a href={home}>Live view</a>}
        <span class="badge connection" data-status={connection.value}>{connection.value}</span>
        <output class="status" role="status" data-ok={String(s.ok)}>{s.text}</output>
      </header>
      <main class="debug-page">
        {drawn.value.map((m) => (
          <Card d={m} />
        ))}
        {!drawn.value.length && <p class="hint">No machine yet.</p>}
      </main>
    </>
  );
}

export function start(): void {
  connect(
    receive,
    () => (connection.value = "live"),
    () => (connection.value = "closed"),
  );
}
