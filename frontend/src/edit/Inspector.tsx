// What the selection is made of, as forms: a state (its name, initial and suspend, its
// transitions, its code), a transition (target, priority, guard), and the machine's own files.
// Every structure operation is a field or a button here or in the toolbar: nothing needs the
// pointer.

import { useEffect, useRef, useState } from "preact/hooks";
import { Code } from "./Code";
import { MACHINE_FILES, STATE_SECTIONS, stateFile } from "./files";
import { buffer, edited, type Full, machine, operate, resolve, selection, type StateInfo } from "./store";
import { Conflict } from "./Conflict";

function FileEditor(props: { m: Full; file: string; label: string }) {
  const b = buffer(props.m.key, props.file);
  const ext = b.external.value;
  const conflict = b.conflict.value;
  const diags = props.m.diagnostics.filter((d) => d.file === props.file);
  return (
    <div class="field code-field" data-file={props.file}>
      <span class="label">{props.label} <span class="file">{props.file}</span></span>
      <Code
        label={props.label}
        file={props.file}
        text={b.text}
        revision={ext.n}
        python={!props.file.endsWith(".yaml")}
        onChange={(t) => edited(b, t)}
        diagnostics={diags}
      />
      {conflict !== undefined && <Conflict buffer={b} disk={conflict} onChoose={(k) => resolve(b, k)} />}
    </div>
  );
}

/** A text field whose value is applied when committed (Enter or leaving it), not per key. */
function Committed(props: { label: string; value: string; onCommit: (v: string) => void; type?: string; min?: number; max?: number }) {
  const [v, setV] = useState(props.value);
  useEffect(() => setV(props.value), [props.value]);
  const commit = () => {
    if (v !== props.value) props.onCommit(v);
  };
  return (
    <label>
      {props.label}{" "}
      <input
        type={props.type ?? "text"}
        value={v}
        min={props.min}
        max={props.max}
        spellcheck={false}
        onInput={(e) => setV(e.currentTarget.value)}
        onBlur={commit}
        onKeyDown={(e) => {
          if (e.key === "Enter") {
            e.preventDefault();
            commit();
          }
        }}
      />
    </label>
  );
}

function StatePanel(props: { m: Full; s: StateInfo }) {
  const { m, s } = props;
  const st = m.structure!;
  return (
    <section class="panel" aria-label={`state ${s.name}`}>
      <h2>State {s.name}</h2>
      <Committed
        label="Name"
        value={s.name}
        onCommit={async (v) => {
          if (await operate("state_rename", { old: s.name, new: v.trim() })) selection.value = { state: v.trim() };
        }}
      />
      <div class="checks">
        <label>
          <input
            type="checkbox"
            checked={st.initial === s.name}
            onChange={(e) => {
              if (e.currentTarget.checked) void operate("set_initial", { state: s.name });
              else e.currentTarget.checked = true; // a machine always has an initial state: choose another one
            }}
          />{" "}
          Initial state
        </label>
        <label>
          <input
            type="checkbox"
            checked={st.suspend === s.name}
            onChange={(e) => void operate("set_suspend", { state: e.currentTarget.checked ? s.name : null })}
          />{" "}
          Suspend state
        </label>
      </div>
      <h3>Transitions, by priority</h3>
      {s.transitions.length ? (
        <ul class="transitions">
          {s.transitions.map((t) => (
            <li>
              <button type="button" class="link" onClick={() => (selection.value = { transition: { source: s.name, index: t.index } })}>
                {t.index} → {t.target}: <code>{t.guard || "(no guard)"}</code>
              </button>
            </li>
          ))}
        </ul>
      ) : (
        <p class="hint">None: an accepting state (the machine ends here).</p>
      )}
      {STATE_SECTIONS.map((x) => (
        <FileEditor key={`${m.key}/${s.name}/${x.suffix}`} m={m} file={stateFile(s.name, x.suffix)} label={x.label} />
      ))}
    </section>
  );
}

function TransitionPanel(props: { m: Full; source: string; index: number }) {
  const { m, source, index } = props;
  const s = m.structure!.states.find((x) => x.name === source);
  const t = s?.transitions[index];
  const [guard, setGuard] = useState(t?.guard ?? "");
  useEffect(() => setGuard(t?.guard ?? ""), [t?.guard, source, index]);
  if (!s || !t) return <p class="hint">That transition is gone.</p>;
  const commitGuard = (g: string) => {
    if (g.trim() && g.trim() !== t.guard) void operate("set_guard", { source, index, guard: g.trim() });
  };
  return (
    <section class="panel" aria-label={`transition ${index} of ${source}`}>
      <h2>
        Transition {index} of {source}
      </h2>
      <label>
        Target{" "}
        <select
          value={t.target}
          onChange={(e) => void operate("transition_retarget", { source, index, target: e.currentTarget.value })}
        >
          {m.structure!.states.map((x) => (
            <option value={x.name}>{x.name}</option>
          ))}
        </select>
      </label>
      <Committed
        label="Priority"
        type="number"
        min={0}
        max={s.transitions.length - 1}
        value={String(index)}
        onCommit={async (v) => {
          const to = Number(v);
          if (Number.isInteger(to) && (await operate("transition_move", { source, index, to })))
            selection.value = { transition: { source, index: to } };
        }}
      />
      <div class="field">
        <span class="label">Guard {t.file ? <span class="file">{t.file}</span> : <span class="file">inline in machine.yaml</span>}</span>
        <Code
          key={`${m.key}/${source}/${index}`}
          label="Guard"
          text={guard}
          revision={0}
          oneLine
          onChange={setGuard}
          onCommit={commitGuard}
          file={t.file ?? undefined}
          diagnostics={t.file ? m.diagnostics.filter((d) => d.file === t.file) : []}
        />
      </div>
      <button type="button" class="link" onClick={() => (selection.value = { state: source })}>
        Back to state {source}
      </button>
    </section>
  );
}

function MachinePanel(props: { m: Full }) {
  const { m } = props;
  const known = new Set<string>(MACHINE_FILES.map((f) => f.file));
  const [other, setOther] = useState("machine.yaml");
  const files = Object.keys(m.files).filter((f) => !known.has(f));
  if (!files.includes("machine.yaml")) files.unshift("machine.yaml");
  return (
    <section class="panel" aria-label={`machine ${m.name}`}>
      <h2>Machine {m.name}</h2>
      <DescriptionEditor m={m} />
      {MACHINE_FILES.map((f) => (
        <FileEditor key={`${m.key}/${f.file}`} m={m} file={f.file} label={f.label} />
      ))}
      <details class="files">
        <summary>Every file</summary>
        <label>
          File{" "}
          <select value={other} onChange={(e) => setOther(e.currentTarget.value)}>
            {files.map((f) => (
              <option value={f}>{f}</option>
            ))}
          </select>
        </label>
        <FileEditor key={`${m.key}/${other}`} m={m} file={other} label={other} />
      </details>
    </section>
  );
}

/** The description is machine.yaml's: written a little after typing stops (each write is a
 * structure operation: machine.yaml is rewritten with its comments kept). */
const DESCRIPTION_DELAY = 400;

function DescriptionEditor(props: { m: Full }) {
  const { m } = props;
  const text = m.structure?.description ?? "";
  const [rev, setRev] = useState(0);
  const [value, setValue] = useState(text);
  useEffect(() => {
    setValue(text);
    setRev((r) => r + 1);
  }, [text, m.key]);
  const timer = useRef<ReturnType<typeof setTimeout> | null>(null);
  const commit = (v: string) => {
    if (timer.current) clearTimeout(timer.current);
    timer.current = null;
    if (v.trim() !== text.trim()) void operate("set_description", { text: v });
  };
  const changed = (v: string) => {
    setValue(v);
    if (timer.current) clearTimeout(timer.current);
    timer.current = setTimeout(() => commit(v), DESCRIPTION_DELAY);
  };
  return (
    <div class="field">
      <span class="label">Description <span class="file">machine.yaml</span></span>
      <Code label="Description" text={value} revision={rev} python={false} onChange={changed} onCommit={commit} />
    </div>
  );
}

export function Inspector() {
  const m = machine.value;
  if (!m) return <p class="hint">Open a machine (left), or make one with New machine.</p>;
  const sel = selection.value;
  const s = sel?.state ? m.structure?.states.find((x) => x.name === sel.state) : undefined;
  return (
    <>
      {m.stale && <p class="warning">machine.yaml does not read now: the diagram is the last one that did (see Problems).</p>}
      {s && <StatePanel m={m} s={s} />}
      {sel?.transition && m.structure && <TransitionPanel m={m} source={sel.transition.source} index={sel.transition.index} />}
      <MachinePanel m={m} />
    </>
  );
}

