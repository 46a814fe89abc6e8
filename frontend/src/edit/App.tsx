// `llfsm edit`'s page: the toolbar, the machines, the diagram, the inspector, the problems.

import { useEffect, useState } from "preact/hooks";
import { Controls } from "../debug/Controls";
import { debug, marksOf, shownMachine, toggleBreakpoint } from "../debug/store";
import { Variables } from "../debug/Variables";
import { Diagram, zoomDiagram } from "../diagram/Diagram";
import { dialog, Dialogs } from "./Dialogs";
import { ownerOf, problemStates, stateLines } from "./files";
import { reveal } from "./Code";
import { Inspector } from "./Inspector";
import {
  command,
  connection,
  live,
  machine,
  machines,
  open,
  operate,
  redoCount,
  run,
  saveAll,
  selection,
  shown,
  startRun,
  status,
  stopRun,
  undo,
  undoCount,
  unsaved,
} from "./store";

function Toolbar() {
  const m = machine.value;
  const sel = selection.value;
  const editable = !!m?.structure;
  const remove = () => {
    if (sel?.transition) {
      void operate("transition_remove", sel.transition).then((ok) => ok && (selection.value = { state: sel.transition!.source }));
    } else if (sel?.state) {
      void operate("state_remove", { name: sel.state }).then((ok) => ok && (selection.value = null));
    }
  };
  return (
    <div role="toolbar" aria-label="Edit" class="toolbar">
      <button type="button" onClick={() => (dialog.value = "machine")}>New machine</button>
      <button type="button" disabled={!editable} onClick={() => (dialog.value = "state")}>Add state</button>
      <button type="button" disabled={!editable} onClick={() => (dialog.value = "transition")}>Add transition</button>
      <button type="button" disabled={!sel} onClick={remove}>Delete</button>
      <button type="button" disabled={!undoCount.value} onClick={() => void undo()}>Undo</button>
      <button type="button" disabled={!redoCount.value} onClick={() => void undo(true)}>Redo</button>
    </div>
  );
}

function RunBar() {
  const r = run.value;
  const [clock, setClock] = useState("wall");
  const [nodes, setNodes] = useState("");
  const [duration, setDuration] = useState("");
  const running = r.state === "running" || r.state === "starting";
  return (
    <div role="toolbar" aria-label="Run" class="toolbar run">
      <label>
        Clock{" "}
        <select value={clock} onChange={(e) => setClock(e.currentTarget.value)}>
          <option value="wall">wall</option>
          <option value="sim">sim</option>
        </select>
      </label>
      <label>
        Nodes <input class="nodes" value={nodes} placeholder="turtlesim" spellcheck={false} onInput={(e) => setNodes(e.currentTarget.value)} />
      </label>
      <label>
        Duration (s) <input class="duration" type="number" min={0} value={duration} onInput={(e) => setDuration(e.currentTarget.value)} />
      </label>
      <button
        type="button"
        disabled={running}
        onClick={() => void startRun(clock, nodes.split(/[\s,]+/).filter(Boolean), duration ? Number(duration) : null)}
      >
        Run
      </button>
      <button type="button" disabled={!running} onClick={() => void stopRun()}>Stop</button>
      <span class="badge" data-status={r.state} role="status" aria-label="run status">{r.state === "idle" ? "not running" : r.state}</span>
      {running && <Controls disabled={r.state !== "running"} />}
    </div>
  );
}

/** A name that wraps only after its underscores (`ros2_wall_turtle_bot`), never inside a word. */
function breakable(name: string) {
  return name.split(/(?<=_)/).flatMap((part, i) => (i ? [<wbr />, part] : [part]));
}

function MachineList() {
  return (
    <nav aria-label="Machines" class="machines">
      <h2>Machines</h2>
      <ul>
        {machines.value.map((m) => (
          <li>
            <button
              type="button"
              aria-current={shown.value === m.key ? "true" : undefined}
              data-machine={m.key}
              onClick={() => void open(m.key)}
              title={m.folder}
            >
              <span class="name">{breakable(m.name)}</span>
              {m.errors ? <span class="count error">{m.errors}</span> : null}
              {m.warnings ? <span class="count warning">{m.warnings}</span> : null}
            </button>
          </li>
        ))}
      </ul>
      {!machines.value.length && <p class="hint">No machine here yet: New machine makes one.</p>}
    </nav>
  );
}

function Problems() {
  const m = machine.value;
  const diags = m?.diagnostics ?? [];
  const names = m?.structure?.states.map((s) => s.name) ?? [];
  return (
    <section class="problems" aria-labelledby="problems-title">
      <h2 id="problems-title">Problems {diags.length ? `(${diags.length})` : ""}</h2>
      <ul aria-label="Problems">
        {diags.map((d) => (
          <li data-severity={d.severity} data-code={d.code} data-file={d.file}>
            <button
              type="button"
              class="link"
              onClick={() => {
                const owner = ownerOf(d.file, names);
                if (owner?.transition !== undefined) selection.value = { transition: { source: owner.state, index: owner.transition } };
                else if (owner) selection.value = { state: owner.state };
                // once the state's editors are on the page: the file's, at the problem's place
                let tries = 20;
                const go = () => reveal(d.file, d.line, d.column) || (--tries > 0 && setTimeout(go, 25));
                requestAnimationFrame(() => void go());
              }}
            >
              <span class="where">
                {d.file || m?.name}:{d.line}:{d.column}
              </span>{" "}
              <span class="rule">{d.code}</span> <span class="sev">{d.severity}</span>: {d.message}
            </button>
          </li>
        ))}
      </ul>
      {!diags.length && m && <p class="hint clean">No problems: llfsm check is clean.</p>}
    </section>
  );
}

function Canvas() {
  const m = machine.value;
  if (!m) return <section class="canvas" />;
  const names = m.structure?.states.map((s) => s.name) ?? [];
  const marks = problemStates(m.diagnostics, names, stateLines(m.files["machine.yaml"] ?? ""));
  const l = live.value.machines[m.name];
  const r = run.value;
  const inRun = r.machines.includes(m.name) && (r.state === "running" || r.state === "ended");
  const debugging = inRun && r.state === "running";
  const shownState = inRun ? shownMachine(m.name, l?.state ?? null).state : null;
  return (
    <section class="canvas" aria-label={`diagram of ${m.name}`}>
      <div class="canvas-bar">
        <h2>{m.name}</h2>
        <span class="zoom">
          <button type="button" onClick={() => zoomDiagram(m.name, "in")}>Zoom in</button>
          <button type="button" onClick={() => zoomDiagram(m.name, "out")}>Zoom out</button>
          <button type="button" onClick={() => zoomDiagram(m.name, "fit")}>Fit</button>
        </span>
        {inRun && (
          <span class="live" data-status={l?.status ?? ""}>
            {l ? `${l.status} in ${l.state ?? "…"}` : "waiting for the run"}{" "}
            <button type="button" disabled={r.state !== "running"} onClick={() => void command(m.name, "suspend")}>Suspend</button>
            <button type="button" disabled={r.state !== "running"} onClick={() => void command(m.name, "resume")}>Resume</button>
            <button type="button" disabled={r.state !== "running"} onClick={() => void command(m.name, "restart")}>Restart</button>
          </span>
        )}
      </div>
      {m.svg ? (
        <Diagram
          machine={m.name}
          svg={m.svg}
          selected={selection.value}
          current={shownState}
          marks={marks}
          breakpoints={debugging ? marksOf(m.name, debug.value.breaks) : undefined}
          onToggleBreakpoint={debugging ? (sel) => void toggleBreakpoint(m.name, sel) : undefined}
          onSelect={(s) => (selection.value = s)}
          onMove={(positions) => void operate("set_layout", { positions })}
          onMoveLabel={(t, corner) => void operate("set_layout", { positions: {}, labels: [{ ...t, x: corner[0], y: corner[1] }] })}
        />
      ) : (
        <p class="hint">machine.yaml does not read yet: see Problems.</p>
      )}
      {debugging && <Variables machine={m.name} liveState={l?.state ?? null} />}
      <Problems />
      {r.output.length > 0 && (
        <details class="output">
          <summary>Run output ({r.output.length} lines)</summary>
          <pre>{r.output.join("\n")}</pre>
        </details>
      )}
    </section>
  );
}

export function App() {
  useEffect(() => {
    const keys = (e: KeyboardEvent) => {
      const inCode = (e.target as Element | null)?.closest?.(".cm-editor, input, select, textarea");
      if ((e.ctrlKey || e.metaKey) && e.key.toLowerCase() === "s") {
        e.preventDefault();
        void saveAll();
      } else if ((e.ctrlKey || e.metaKey) && !inCode && e.key.toLowerCase() === "z") {
        e.preventDefault();
        void undo(e.shiftKey);
      } else if ((e.ctrlKey || e.metaKey) && !inCode && e.key.toLowerCase() === "y") {
        e.preventDefault();
        void undo(true);
      }
    };
    window.addEventListener("keydown", keys);
    return () => window.removeEventListener("keydown", keys);
  }, []);
  const s = status.value;
  return (
    <>
      <header class="top">
        <h1>llfsm edit</h1>
        <Toolbar />
        <RunBar />
        <span class="badge connection" data-status={connection.value}>{connection.value}</span>
        {unsaved.value > 0 && <span class="unsaved">{unsaved.value} unsaved</span>}
        <output class="status" role="status" data-ok={String(s.ok)}>{s.text}</output>
      </header>
      <main class="edit">
        <MachineList />
        <Canvas />
        <aside class="inspector" aria-label="Inspector">
          <Inspector />
        </aside>
      </main>
      <Dialogs />
    </>
  );
}
