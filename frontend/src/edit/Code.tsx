// A code editor (CodeMirror 6): Python highlighting, line numbers, indentation, undo, search
// (Ctrl+F), and `check`'s diagnostics as lint marks at their line and column.  Labelled for
// assistive technology and tests (SPEC 13: "OnEntry", "Variables", ...).  One line for a guard.

import { autocompletion, closeBrackets, closeBracketsKeymap } from "@codemirror/autocomplete";
import { defaultKeymap, history, historyKeymap, indentWithTab } from "@codemirror/commands";
import { python } from "@codemirror/lang-python";
import { bracketMatching, defaultHighlightStyle, indentOnInput, syntaxHighlighting } from "@codemirror/language";
import { type Diagnostic as LintDiagnostic, lintGutter, setDiagnostics } from "@codemirror/lint";
import { highlightSelectionMatches, searchKeymap } from "@codemirror/search";
import { Annotation, EditorState, type Extension, type Text } from "@codemirror/state";
import {
  drawSelection,
  EditorView,
  highlightActiveLine,
  highlightActiveLineGutter,
  keymap,
  lineNumbers,
} from "@codemirror/view";
import { useEffect, useRef } from "preact/hooks";
import type { Diagnostic } from "./files";

/** The page's Content-Security-Policy lets style sheets with this nonce in (the server's). */
export const styleNonce = document.querySelector<HTMLMetaElement>('meta[name="llfsm-style-nonce"]')?.content ?? "";

/** A change made from outside (the disk, undo): not the user's typing. */
const fromOutside = Annotation.define<boolean>();

export interface CodeProps {
  label: string;
  text: string;
  /** Bumped when `text` comes from outside and must replace what the editor shows. */
  revision: number;
  onChange: (text: string) => void;
  diagnostics?: readonly Diagnostic[];
  oneLine?: boolean;
  python?: boolean;
  readOnly?: boolean;
  /** Enter in a one-line editor, or leaving it. */
  onCommit?: (text: string) => void;
  /** The file it edits: a problem in the list goes to its line here (`reveal`). */
  file?: string;
}

/** The code editors on the page, by the file each edits. */
const open = new Map<string, EditorView>();

/** Put the cursor at a line and column of a file's editor, scrolled into view and focused;
 * false if no editor of that file is on the page. */
export function reveal(file: string, line: number, column: number): boolean {
  const v = open.get(file);
  if (!v) return false;
  const l = v.state.doc.line(Math.min(Math.max(1, line), v.state.doc.lines));
  const pos = Math.min(l.from + Math.max(0, column - 1), l.to);
  v.dispatch({ selection: { anchor: pos }, effects: EditorView.scrollIntoView(pos, { y: "center" }) });
  v.focus();
  return true;
}

export function Code(props: CodeProps) {
  const host = useRef<HTMLDivElement>(null);
  const view = useRef<EditorView | null>(null);
  const latest = useRef(props);
  latest.current = props;

  useEffect(() => {
    const v = new EditorView({ parent: host.current as HTMLElement, state: EditorState.create({ doc: props.text, extensions: extensions(latest) }) });
    view.current = v;
    const file = props.file;
    if (file) open.set(file, v);
    return () => {
      if (file && open.get(file) === v) open.delete(file);
      v.destroy();
    };
  }, [props.oneLine, props.readOnly, props.file]);

  useEffect(() => {
    const v = view.current;
    if (!v || v.state.doc.toString() === props.text) return;
    v.dispatch({ changes: { from: 0, to: v.state.doc.length, insert: props.text }, annotations: fromOutside.of(true) });
  }, [props.revision, props.text]);

  useEffect(() => {
    const v = view.current;
    if (!v) return;
    v.dispatch(setDiagnostics(v.state, toLint(v.state.doc, props.diagnostics ?? [])));
  }, [props.diagnostics, props.revision]);

  return <div class={props.oneLine ? "code one-line" : "code"} ref={host} />;
}

function extensions(latest: { current: CodeProps }): Extension[] {
  const p = latest.current;
  const changed = EditorView.updateListener.of((u) => {
    if (u.docChanged && !u.transactions.some((t) => t.annotation(fromOutside))) latest.current.onChange(u.state.doc.toString());
    if (u.focusChanged && !u.view.hasFocus) latest.current.onCommit?.(u.state.doc.toString());
  });
  const common: Extension[] = [
    changed,
    history(),
    drawSelection(),
    syntaxHighlighting(defaultHighlightStyle, { fallback: true }),
    bracketMatching(),
    closeBrackets(),
    highlightSelectionMatches(),
    EditorView.contentAttributes.of({ "aria-label": p.label, spellcheck: "false", autocapitalize: "off" }),
    EditorState.readOnly.of(!!p.readOnly),
    lintGutter(),
    EditorView.cspNonce.of(styleNonce),
  ];
  if (p.python !== false) common.push(python());
  else common.push(EditorView.lineWrapping); // prose (a description) and YAML wrap
  if (p.oneLine) {
    return [
      ...common,
      EditorState.transactionFilter.of((tr) => (tr.newDoc.lines > 1 ? [] : tr)),
      keymap.of([
        { key: "Enter", run: (v) => (latest.current.onCommit?.(v.state.doc.toString()), true) },
        ...closeBracketsKeymap,
        ...defaultKeymap,
        ...historyKeymap,
      ]),
    ];
  }
  return [
    ...common,
    lineNumbers(),
    highlightActiveLine(),
    highlightActiveLineGutter(),
    indentOnInput(),
    autocompletion({ activateOnTyping: false }),
    keymap.of([...closeBracketsKeymap, ...defaultKeymap, ...searchKeymap, ...historyKeymap, indentWithTab]),
  ];
}

/** `check`'s diagnostics (1-based line and column) as CodeMirror's (document offsets). */
export function toLint(doc: Text, diagnostics: readonly Diagnostic[]): LintDiagnostic[] {
  const out: LintDiagnostic[] = [];
  for (const d of diagnostics) {
    const line = doc.line(Math.min(Math.max(1, d.line), doc.lines));
    // at the end of a line (`count +=`): the last character, so that the mark can be seen
    const from = Math.max(line.from, Math.min(line.from + Math.max(0, d.column - 1), line.to - 1));
    const to = from < line.to ? Math.max(from + 1, Math.min(line.to, wordEnd(line.text, from - line.from) + line.from)) : from;
    out.push({
      from,
      to,
      severity: d.severity === "error" ? "error" : d.severity === "warning" ? "warning" : "info",
      message: d.code ? `${d.code}: ${d.message}` : d.message,
    });
  }
  return out;
}

function wordEnd(text: string, at: number): number {
  const m = /^[A-Za-z0-9_.]+/.exec(text.slice(at));
  return at + (m ? m[0].length : 1);
}
