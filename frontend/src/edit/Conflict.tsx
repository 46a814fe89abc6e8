// A file changed on disk while the page held unsaved edits of it: both versions side by side
// (CodeMirror's merge view), nothing written until the user chooses.

import { MergeView } from "@codemirror/merge";
import { EditorState } from "@codemirror/state";
import { EditorView } from "@codemirror/view";
import { useEffect, useRef } from "preact/hooks";
import { styleNonce } from "./Code";
import type { Buffer } from "./store";

export function Conflict(props: { buffer: Buffer; disk: string | null; onChoose: (keep: "mine" | "theirs") => void }) {
  const host = useRef<HTMLDivElement>(null);
  useEffect(() => {
    const ro = [EditorState.readOnly.of(true), EditorView.editable.of(false), EditorView.cspNonce.of(styleNonce)];
    const view = new MergeView({
      a: { doc: props.buffer.text, extensions: [...ro, EditorView.contentAttributes.of({ "aria-label": "Your version" })] },
      b: { doc: props.disk ?? "", extensions: [...ro, EditorView.contentAttributes.of({ "aria-label": "Version on disk" })] },
      parent: host.current as HTMLElement,
    });
    return () => view.destroy();
  }, [props.disk, props.buffer.text]);
  return (
    <div class="conflict" role="alert" aria-label={`Conflict in ${props.buffer.file}`}>
      <p>
        <strong>{props.buffer.file}</strong> changed on disk while you were editing it
        {props.disk === null ? " (it was deleted)" : ""}. Left: your version (not saved); right: the disk's. Nothing
        is lost until you choose.
      </p>
      <div class="merge" ref={host} />
      <div class="buttons">
        <button type="button" onClick={() => props.onChoose("mine")}>Keep mine</button>
        <button type="button" onClick={() => props.onChoose("theirs")}>Take theirs</button>
      </div>
    </div>
  );
}
