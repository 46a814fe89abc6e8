// The live view's messages (docs/view.md, "The page's channel": protocol 1, a hello whose
// snapshot holds everything, then deltas of what changed) reduced to what a diagram shows of a
// run: each machine's current state and status, the run's time and whether it ended.  The
// editor's Run relays a child run's messages here (`live`); the view and the debugger read the same.

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

/** The channel's version this reader speaks (llfsm/web/channel.py's PROTOCOL). */
export const PROTOCOL = 1;

type Msg = Record<string, unknown>;

function machineOf(m: Msg): [string, LiveMachine] | null {
  const name = String(m.machine ?? m.name ?? "");
  if (!name) return null;
  return [
    name,
    {
      state: typeof m.state === "string" ? m.state : null,
      status: String(m.status ?? ""),
      pending: typeof m.pending === "string" && m.pending ? m.pending : null,
      since: Number(m.since ?? 0),
    },
  ];
}

/** The run after one message: a hello replaces what was known, a delta changes what it names. */
export function reduce(live: Live, msg: Msg): Live {
  let base: Live;
  let delta: Msg;
  if (msg.type === "hello") {
    if (msg.protocol !== PROTOCOL) return live; // another protocol: nothing here can be read
    base = NO_RUN;
    delta = (msg.snapshot as Msg | undefined) ?? {};
  } else if (msg.type === "delta") {
    base = live;
    delta = msg;
  } else {
    return live;
  }
  const header = (delta.header as Msg | undefined) ?? {};
  const machines: Record<string, LiveMachine> = { ...base.machines };
  const change = (delta.machines as Msg | undefined) ?? {};
  for (const gone of (change.remove as unknown[] | undefined) ?? []) delete machines[String(gone)];
  for (const row of (change.upsert as Msg[] | undefined) ?? []) {
    const named = machineOf(row);
    if (named) machines[named[0]] = named[1];
  }
  return {
    t: header.t !== undefined ? Number(header.t) : base.t,
    clock: header.clock !== undefined ? String(header.clock) : base.clock,
    ended: header.ended !== undefined ? Boolean(header.ended) : base.ended,
    machines,
  };
}
