// The forms behind "New machine", "Add state" and "Add transition": modal dialogs, so that a
// keyboard alone does everything (nothing needs a drag) and the fields' names ("Name",
// "Target", "Guard") are the only ones on the page while a dialog is open.

import { signal } from "@preact/signals";
import type { ComponentChildren } from "preact";
import { useEffect, useRef, useState } from "preact/hooks";
import { Code } from "./Code";
import { folders, machine, newMachine, operate, selection } from "./store";

export const dialog = signal<null | "machine" | "state" | "transition">(null);

function Modal(props: { title: string; onSubmit: () => Promise<boolean>; children: ComponentChildren; submit: string }) {
  const ref = useRef<HTMLDialogElement>(null);
  const [busy, setBusy] = useState(false);
  useEffect(() => {
    const d = ref.current;
    if (d && !d.open) d.showModal();
  }, []);
  return (
    <dialog ref={ref} aria-label={props.title} onClose={() => (dialog.value = null)}>
      <form
        method="dialog"
        onSubmit={async (e) => {
          e.preventDefault();
          setBusy(true);
          const ok = await props.onSubmit();
          setBusy(false);
          if (ok) ref.current?.close();
        }}
      >
        <h2>{props.title}</h2>
        {props.children}
        <div class="buttons">
          <button type="submit" disabled={busy}>{props.submit}</button>
          <button type="button" onClick={() => ref.current?.close()}>Cancel</button>
        </div>
      </form>
    </dialog>
  );
}

function NewMachine() {
  const [name, setName] = useState("");
  const [states, setStates] = useState("");
  const [folder, setFolder] = useState(0);
  return (
    <Modal
      title="New machine"
      submit="Make"
      onSubmit={() => newMachine(name.trim(), states.split(/[\s,]+/).filter(Boolean), folder)}
    >
      {folders.value.length > 1 && (
        <label>
          Folder{" "}
          <select value={folder} onChange={(e) => setFolder(Number(e.currentTarget.value))}>
            {folders.value.map((f, i) => (
              <option value={i}>{f}</option>
            ))}
          </select>
        </label>
      )}
      <label>Name <input name="name" required value={name} onInput={(e) => setName(e.currentTarget.value)} autoFocus spellcheck={false} /></label>
      <label>States <input name="states" placeholder="INITIAL, PUBLISH, END (optional)" value={states} onInput={(e) => setStates(e.currentTarget.value)} spellcheck={false} /></label>
    </Modal>
  );
}

function AddState() {
  const [name, setName] = useState("");
  return (
    <Modal
      title="Add state"
      submit="Add"
      onSubmit={async () => {
        const ok = await operate("state_add", { name: name.trim() });
        if (ok) selection.value = { state: name.trim() };
        return ok;
      }}
    >
      <label>Name <input name="name" required value={name} onInput={(e) => setName(e.currentTarget.value)} autoFocus spellcheck={false} /></label>
    </Modal>
  );
}

function AddTransition() {
  const m = machine.value;
  const names = m?.structure?.states.map((s) => s.name) ?? [];
  const [source, setSource] = useState(selection.value?.state ?? selection.value?.transition?.source ?? names[0] ?? "");
  const [target, setTarget] = useState(names[0] ?? "");
  const [guard, setGuard] = useState("");
  return (
    <Modal
      title="Add transition"
      submit="Add"
      onSubmit={async () => {
        const ok = await operate("transition_add", { source, target, guard: guard.trim() || "True" });
        if (ok) {
          const s = machine.value?.structure?.states.find((x) => x.name === source);
          if (s?.transitions.length) selection.value = { transition: { source, index: s.transitions.length - 1 } };
        }
        return ok;
      }}
    >
      <label>Source <select name="source" value={source} onChange={(e) => setSource(e.currentTarget.value)}>{names.map((n) => <option value={n}>{n}</option>)}</select></label>
      <label>Target <select name="target" value={target} onChange={(e) => setTarget(e.currentTarget.value)}>{names.map((n) => <option value={n}>{n}</option>)}</select></label>
      <div class="field"><span class="label">Guard</span><Code label="Guard" text="" revision={0} oneLine onChange={setGuard} /></div>
    </Modal>
  );
}

export function Dialogs() {
  switch (dialog.value) {
    case "machine":
      return <NewMachine />;
    case "state":
      return <AddState />;
    case "transition":
      return <AddTransition />;
    default:
      return null;
  }
}
