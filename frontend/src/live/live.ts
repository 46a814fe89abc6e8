// The live view's messages (docs/view.md) reduced to what a diagram shows of a run: each
// machine's current state and status, the run's time and whether it ended.  The editor's Run
// relays a child run's messages here (`live`); the view and the debugger read the same.

export interface LiveMachine {
  state: string | null;
  status: string;
  pending: string | null;
  since: number;
}

export interface Live {
  t: number;
  clock: string;
  ended: boolean;
  machines: Record<string, LiveMachine>;
}

export const NO_RUN: Live = { t: 0, clock: "", ended: false, machines: {} };

type Msg = Record<string, unknown>;

export function reduce(live: Live, msg: Msg): Live {
  const snap = msg.type === "hello" ? (msg.snapshot as Msg | undefined) : msg.type === "snapshot" ? msg : undefined;
  if (!snap) return live;
  const machines: Record<string, LiveMachine> = { ...live.machines };
  for (const m of (snap.machines as Msg[] | undefined) ?? []) {
    const name = String(m.machine ?? m.name ?? "");
    if (!name) continue;
    machines[name] = {
      state: typeof m.state === "string" ? m.state : null,
      status: String(m.status ?? ""),
      pending: typeof m.pending === "string" && m.pending ? m.pending : null,
      since: Number(m.since ?? 0),
    };
  }
  return {
    t: Number(snap.t ?? live.t),
    clock: String(snap.clock ?? live.clock),
    ended: Boolean(snap.ended),
    machines,
  };
}
