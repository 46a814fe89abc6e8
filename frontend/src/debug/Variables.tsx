// "Variables of M": a machine's variables and inputs as the run last took them (or as the
// History slider shows them), each settable while the run is paused (typed by its annotation on
// the run's side: a refusal comes back as one line).

import { useState } from "preact/hooks";
import { debug, frame, setValue, shownMachine } from "./store";

function text(v: unknown): string {
  return typeof v === "string" ? v : JSON.stringify(v);
}

export function Variables(props: { machine: string; name?: string; liveState?: string | null }) {
  const m = props.machine;
  const shown = shownMachine(m, props.liveState ?? null);
  const editable = debug.value.paused && !frame.value && !debug.value.replay;
  const names = Object.keys(shown.values);
  return (
    <table class="variables" aria-label={`Variables of ${props.name ?? m}`}>
      <caption>Variables of {props.name ?? m}</caption>
      <tbody>
        {names.map((n) => (
          <Row machine={m} name={n} value={shown.values[n]} editable={editable} />
        ))}
        {!names.length && (
          <tr>
            <td class="hint" colSpan={2}>{debug.value.records ? "no variables" : "pause the run to read them"}</td>
          </tr>
        )}
      </tbody>
    </table>
  );
}

function Row(props: { machine: string; name: string; value: unknown; editable: boolean }) {
  const [draft, setDraft] = useState<string | null>(null);
  const shown = text(props.value);
  return (
    <tr data-variable={props.name}>
      <th scope="row">{props.name}</th>
      <td>
        {props.editable ? (
          <input
            aria-label={`${props.name} of ${props.machine}`}
            value={draft ?? shown}
            spellcheck={false}
            onInput={(e) => setDraft(e.currentTarget.value)}
            onKeyDown={(e) => {
              if (e.key === "Enter" && draft !== null) {
                void setValue(props.machine, props.name, draft).then((r) => r.success && setDraft(null));
              } else if (e.key === "Escape") {
                setDraft(null);
              }
            }}
          />
        ) : (
          <code>{shown}</code>
        )}
      </td>
    </tr>
  );
}
