// The debugger's state in the page (docs/debug.md, "The page"): what the run's snapshots say of
// it (the `debug` part, llfsm/web/debugging.py), the record the History slider shows, and the
// requests its controls send (`/api/debug/...`: the run's page server, or the editor's, which
// relays them to the run it started).  Views only render these signals.

import { signal } from "@preact/signals";
import { type Answer, post } from "../api";

export interface DebugState {
  paused: boolean;
  where: string;
  reason: string;
  /** The machine whose ringlet the pause follows. */
  machine: string | null;
  /** The run's breakpoints, as written. */
  breaks: string[];
  /** Each machine's variables and inputs, as the run last took them. */
  variables: Record<string, Record<string, unknown>>;
  /** Records the history keeps (0: none: a view of another process). */
  records: number;
  /** A replay: "trace" or "counterexample" (nothing runs: only the History slider moves). */
  replay?: string;
  /** `llfsm view`: each machine's run, as its /llfsm/M/debug says. */
  runs?: Record<string, { paused: boolean; where: string; reason: string; breaks: string[] }>;
}

export interface FrameMachine {
  machine: string;
  state: string;
  values: Record<string, unknown>;
}

export interface HistoryRecord {
  ringlet: number;
  round: number;
  t: number;
  machine: string;
  kind: string;
  before: string;
  state: string | null;
  after: string;
  transition: number | null;
  changed: Record<string, [unknown, unknown]>;
  published: string[];
}

/** The arrangement as it was at a kept record (what the History slider shows). */
export interface Frame {
  record: HistoryRecord | null;
  machines: FrameMachine[];
}

export const NO_DEBUG: DebugState = { paused: false, where: "", reason: "", machine: null, breaks: [], variables: {}, records: 0 };

export const debug = signal<DebugState>(NO_DEBUG);
/** The slider: how many records back from now (0: now, the live run). */
export const back = signal(0);
/** The frame the slider shows (null: now). */
export const frame = signal<Frame | null>(null);
/** The last answer of a control, for the status line. */
export const said = signal<{ text: string; ok: boolean }>({ text: "", ok: true });

type Msg = Record<string, unknown>;

/** Variables after a delta's: the machines it names replaced (null: gone), the others kept. */
function mergeVariables(was: DebugState["variables"], changed: Record<string, Record<string, unknown> | null>): DebugState["variables"] {
  const out = { ...was };
  for (const [m, values] of Object.entries(changed)) {
    if (values === null) delete out[m];
    else out[m] = values;
  }
  return out;
}

/** The channel's `debug` part (docs/view.md, "The page's channel": a hello's snapshot holds it
 * whole; a delta only when it changed, with the variables of the machines whose values changed)
 * into the state. */
export function reduceDebug(msg: Msg): void {
  const hello = msg.type === "hello";
  const part = hello ? (msg.snapshot as Msg | undefined) : msg.type === "delta" ? msg : undefined;
  const d = part?.debug as Msg | null | undefined;
  if (!d) return;
  const changed = (d.variables as Record<string, Record<string, unknown> | null> | undefined) ?? {};
  const next: DebugState = {
    paused: Boolean(d.paused),
    where: String(d.where ?? ""),
    reason: String(d.reason ?? ""),
    machine: typeof d.machine === "string" ? d.machine : null,
    breaks: Array.isArray(d.breaks) ? d.breaks.map(String) : [],
    variables: mergeVariables(hello ? {} : debug.value.variables, changed),
    records: Number(d.records ?? 0),
    replay: typeof d.replay === "string" ? d.replay : undefined,
    runs: (d.runs as DebugState["runs"]) ?? undefined,
  };
  const was = debug.value;
  debug.value = next;
  // a replay starts at its end; a live run shows now until the slider is moved
  if (next.replay && !was.replay) void showFrame(0);
  else if (frame.value && !next.replay && next.paused !== was.paused) {
    back.value = 0;
    frame.value = null; // the run moved on: the slider comes back to now
  }
}

async function request(what: string, body: Record<string, unknown> = {}): Promise<Answer> {
  const r = await post(`/api/debug/${what}`, body);
  said.value = { text: r.message, ok: r.success };
  return r;
}

export const pause = (machine?: string) => request("pause", machine ? { machine } : {});
export const resume = (how: "continue" | "step" | "step_round", machine?: string) => {
  back.value = 0;
  frame.value = null;
  return request(how, machine ? { machine } : {});
};
export const setValue = (machine: string, name: string, value: string) => request("set", { machine, name, value });

/** The slider moved: the arrangement `n` records back (a replay: `n` records before its end). */
export async function showFrame(n: number): Promise<void> {
  back.value = n;
  const d = debug.value;
  if (!d.replay && n === 0) {
    frame.value = null;
    return;
  }
  const r = await request("frame", d.replay ? { at: Math.max(0, d.records - n) } : { back: n });
  if (r.success && back.value === n) frame.value = { record: (r.record as HistoryRecord) ?? null, machines: (r.machines as FrameMachine[]) ?? [] };
}

// -- breakpoints on the diagram ------------------------------------------------------------------

/** The expression a toggle on a state or a transition of machine `m` stands for. */
export function breakExpression(m: string, sel: { state?: string; transition?: { source: string; index: number } }): string | null {
  if (sel.state) return `state(${m}) == ${JSON.stringify(sel.state)}`;
  if (sel.transition) return `fired(${m}, ${JSON.stringify(sel.transition.source)}, ${sel.transition.index})`;
  return null;
}

const STATE = /^state\((\w+)\) == "((?:[^"\\]|\\.)*)"$/;
const FIRED = /^fired\((\w+), "((?:[^"\\]|\\.)*)", (\d+)\)$/;

/** Machine m's breakpoints as the diagram marks them: state names and "SOURCE#INDEX". */
export function marksOf(m: string, breaks: readonly string[]): Set<string> {
  const out = new Set<string>();
  for (const b of breaks) {
    const s = STATE.exec(b);
    if (s && s[1] === m) out.add(JSON.parse(`"${s[2]}"`) as string);
    const f = FIRED.exec(b);
    if (f && f[1] === m) out.add(`${JSON.parse(`"${f[2]}"`) as string}#${f[3]}`);
  }
  return out;
}

/** Toggle the breakpoint on a state or transition of machine `m` (`key`: the page's name for it,
 * which a view needs to reach its run). */
export async function toggleBreakpoint(
  m: string,
  sel: { state?: string; transition?: { source: string; index: number } },
  key: string = m,
): Promise<void> {
  const expression = breakExpression(m, sel);
  if (!expression) return;
  const on = debug.value.breaks.includes(expression);
  const r = await request("breakpoint", { expression, enable: !on, machine: key });
  if (r.success) {
    const breaks = on ? debug.value.breaks.filter((b) => b !== expression) : [...debug.value.breaks, expression];
    debug.value = { ...debug.value, breaks };
  }
}

/** A machine's state and values as the page shows them now: the slider's frame, or the run's. */
export function shownMachine(m: string, liveState: string | null): { state: string | null; values: Record<string, unknown> } {
  const f = frame.value?.machines.find((x) => x.machine === m);
  if (f) return { state: f.state, values: f.values };
  return { state: liveState, values: debug.value.variables[m] ?? {} };
}

/** `llfsm view`: read machine `key`'s variables from its run (a run in another process sends
 * them only when asked). */
export async function readVariables(key: string): Promise<void> {
  const r = await post(`/api/debug/variables`, { machine: key });
  if (!r.success) return;
  const m = r.machine as { variables?: Record<string, unknown>; inputs?: Record<string, unknown> } | undefined;
  const values = { ...(m?.variables ?? {}), ...(m?.inputs ?? {}) };
  debug.value = { ...debug.value, variables: { ...debug.value.variables, [key]: values } };
}

/** A new run: nothing of the last one's debugger is shown. */
export function reset(): void {
  debug.value = NO_DEBUG;
  back.value = 0;
  frame.value = null;
}
