// The machine format's file names (SPEC 1) as the page needs them: which file a code editor
// edits, and which state a diagnostic belongs to (its mark on the diagram).

export const STATE_SECTIONS = [
  { label: "OnEntry", suffix: "OnEntry" },
  { label: "OnExit", suffix: "OnExit" },
  { label: "Internal", suffix: "Internal" },
  { label: "OnSuspend", suffix: "OnSuspend" },
  { label: "OnResume", suffix: "OnResume" },
  { label: "State variables", suffix: "Variables" },
] as const;

export const MACHINE_FILES = [
  { label: "Variables", file: "Variables.py" },
  { label: "Includes", file: "Includes.py" },
] as const;

export function stateFile(state: string, suffix: string): string {
  return `State_${state}_${suffix}.py`;
}

const STATE_FILE = /^State_([A-Za-z_][A-Za-z0-9_]*?)_(OnEntry|OnExit|Internal|OnSuspend|OnResume|Variables)\.py$/;
const GUARD_FILE = /^State_([A-Za-z_][A-Za-z0-9_]*?)_Transition_(\d+)\.expr$/;

/** The state a file belongs to (and the transition, for a guard file), or null. */
export function ownerOf(file: string, states: readonly string[]): { state: string; transition?: number } | null {
  // a state's name may itself hold `_Transition_` or `_OnEntry`: the longest known name wins
  const guard = GUARD_FILE.exec(file);
  if (guard) {
    const s = longest(file, "State_", states, (n) => file === `State_${n}_Transition_${guard[2]}.expr`);
    return s ? { state: s, transition: Number(guard[2]) } : null;
  }
  if (STATE_FILE.test(file)) {
    const s = longest(file, "State_", states, (n) => STATE_SECTIONS.some((x) => file === stateFile(n, x.suffix)));
    return s ? { state: s } : null;
  }
  return null;
}

function longest(file: string, prefix: string, states: readonly string[], ok: (n: string) => boolean): string | null {
  let best: string | null = null;
  for (const n of states) {
    if (file.startsWith(prefix + n + "_") && ok(n) && (!best || n.length > best.length)) best = n;
  }
  return best;
}

export interface Diagnostic {
  code: string;
  severity: string;
  file: string;
  line: number;
  column: number;
  message: string;
}

const RANK: Record<string, number> = { error: 3, warning: 2, info: 1 };

/** States with a problem, each with the worst severity of its problems: a problem in a
 * state's file, or in machine.yaml at a state's own lines (`lines`: state -> [first, last]). */
export function problemStates(
  diagnostics: readonly Diagnostic[],
  states: readonly string[],
  lines: ReadonlyMap<string, [number, number]> = new Map(),
): Map<string, string> {
  const out = new Map<string, string>();
  const put = (s: string, sev: string) => {
    const had = out.get(s);
    if (!had || (RANK[sev] ?? 0) > (RANK[had] ?? 0)) out.set(s, sev);
  };
  for (const d of diagnostics) {
    const owner = ownerOf(d.file, states);
    if (owner) {
      put(owner.state, d.severity);
      continue;
    }
    if (d.file === "machine.yaml") {
      for (const [s, [a, b]] of lines) if (d.line >= a && d.line <= b) put(s, d.severity);
    }
  }
  return out;
}

/** Where each state is written in machine.yaml (first and last line of its entry), read from
 * the text: `- name: S` starts an entry, which runs to the next one. */
export function stateLines(yaml: string): Map<string, [number, number]> {
  const out = new Map<string, [number, number]>();
  const lines = yaml.split("\n");
  let current: string | null = null;
  let start = 0;
  let indent = -1;
  lines.forEach((text, i) => {
    const m = /^(\s*)- name:\s*["']?([A-Za-z_][A-Za-z0-9_]*)/.exec(text);
    if (m && (indent < 0 || m[1].length === indent)) {
      if (current) out.set(current, [start, i]);
      current = m[2];
      start = i + 1;
      indent = m[1].length;
    } else if (current && indent >= 0 && /^\S/.test(text) && !text.startsWith("#")) {
      out.set(current, [start, i]);
      current = null;
    }
  });
  if (current) out.set(current, [start, lines.length]);
  return out;
}
