// The debugger's controls (docs/debug.md, "The page"): Pause, Continue, Step ringlet, Step
// round, the status ("paused" / "running"), where and why it paused, and the History slider.
// Rendered by the editor's run bar and by the run's debugger page; `machine` names a machine of
// the run for a page that reaches runs through their machines (`llfsm view`).

import { back, debug, pause, resume, showFrame } from "./store";

export function Controls(props: { machine?: string; disabled?: boolean; paused?: boolean; where?: string }) {
  const d = debug.value;
  const off = props.disabled ?? false;
  const replay = !!d.replay;
  const paused = props.paused ?? d.paused;
  const where = props.where ?? d.where;
  return (
    <span class="debug" role="group" aria-label="Debugger">
      {!replay && (
        <>
          <button type="button" disabled={off || paused} onClick={() => void pause(props.machine)}>Pause</button>
          <button type="button" disabled={off || !paused} onClick={() => void resume("continue", props.machine)}>Continue</button>
          <button type="button" disabled={off || !paused} onClick={() => void resume("step", props.machine)}>Step ringlet</button>
          <button type="button" disabled={off || !paused} onClick={() => void resume("step_round", props.machine)}>Step round</button>
          <span class="badge" role="status" aria-label="debugger status" data-status={paused ? "paused" : "running"}>
            {paused ? "paused" : "running"}
          </span>
        </>
      )}
      {d.records > 0 && <History />}
      {paused && where && <span class="where">{where}</span>}
    </span>
  );
}

/** The History slider: the right end is now (a replay: its last ringlet), each step left one
 * kept record further back. */
function History() {
  const d = debug.value;
  const n = back.value;
  return (
    <label class="history">
      History{" "}
      <input
        type="range"
        aria-label="History"
        min={0}
        max={d.records}
        value={d.records - n}
        onInput={(e) => void showFrame(d.records - Number(e.currentTarget.value))}
      />{" "}
      <span class="at">{n === 0 ? (d.replay ? "the end" : "now") : `${n} back`}</span>
    </label>
  );
}
