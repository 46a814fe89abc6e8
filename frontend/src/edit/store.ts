// The editor's state, in one place (signals); the views only render it and call these
// actions.  The files on disk are the truth: every buffer knows the version it was edited
// from, saves within a second of the last keystroke (SAVE_DELAY), and a version changed on
// disk under unsaved edits becomes a conflict that keeps both texts until the user chooses.

import { batch, computed, signal } from "@preact/signals";
import { type Answer, type Message, post } from "../api";
import type { Selection } from "../diagram/Diagram";
import { reduceDebug, reset as resetDebug } from "../debug/store";
import { type Live, NO_RUN, reduce } from "../live/live";
import type { Diagnostic } from "./files";

export const SAVE_DELAY = 60; // ms after the last keystroke (a save is also what brings diagnostics)

export interface Transition {
  index: number;
  target: string;
  guard: string;
  file: string | null;
}
export interface StateInfo {
  name: string;
  transitions: Transition[];
}
export interface Structure {
  name: string;
  description: string;
  initial: string;
  suspend: string | null;
  states: StateInfo[];
}
export interface Summary {
  key: string;
  name: string;
  folder: string;
  errors: number;
  warnings: number;
  checked: boolean;
}
export interface Full {
  key: string;
  name: string;
  folder: string;
  files: Record<string, string>;
  versions: Record<string, string>;
  diagnostics: Diagnostic[];
  structure: Structure | null;
  svg: string;
  stale: boolean;
}
export interface RunStatus {
  state: string;
  message: string;
  machines: string[];
  output: string[];
}

export const folders = signal<string[]>([]);
export const machines = signal<Summary[]>([]);
export const shown = signal<string | null>(null);
export const loaded = signal<Record<string, Full>>({});
export const selection = signal<Selection | null>(null);
export const undoCount = signal(0);
export const redoCount = signal(0);
export const status = signal<{ text: string; ok: boolean }>({ text: "", ok: true });
export const connection = signal("connecting");
export const run = signal<RunStatus>({ state: "idle", message: "", machines: [], output: [] });
export const live = signal<Live>(NO_RUN);
/** Files with edits not yet on disk, and files in conflict (both drive the header's note). */
export const unsaved = signal(0);

export const machine = computed<Full | null>(() => (shown.value ? loaded.value[shown.value] ?? null : null));

// -- buffers: one per file being edited ----------------------------------------------------------

export class Buffer {
  readonly machine: string;
  readonly file: string;
  /** The editor's text. */
  text: string;
  /** The disk's text this buffer was edited from, and its version (null: no such file). */
  base: string;
  version: string | null;
  inflight: string | null = null;
  timer: ReturnType<typeof setTimeout> | null = null;
  /** The disk's text while in conflict (null: the file was deleted); undefined: no conflict. */
  readonly conflict = signal<string | null | undefined>(undefined);
  /** The version of the disk's text in conflict (what Keep mine writes over). */
  conflictVersion: string | null = null;
  /** Text put into the editor from outside (a change on disk, undo), with a counter. */
  readonly external = signal<{ text: string; n: number }>({ text: "", n: 0 });

  constructor(machine: string, file: string, text: string, version: string | null) {
    this.machine = machine;
    this.file = file;
    this.text = text;
    this.base = text;
    this.version = version;
  }

  get dirty(): boolean {
    return this.text !== this.base;
  }

  replace(text: string): void {
    this.text = text;
    this.external.value = { text, n: this.external.value.n + 1 };
  }
}

export const buffers = new Map<string, Buffer>();

export function buffer(machineKey: string, file: string): Buffer {
  const k = `${machineKey}\n${file}`;
  let b = buffers.get(k);
  if (!b) {
    const full = loaded.value[machineKey];
    b = new Buffer(machineKey, file, full?.files[file] ?? "", full?.versions[file] ?? null);
    buffers.set(k, b);
  }
  return b;
}

function countUnsaved(): void {
  let n = 0;
  for (const b of buffers.values()) if (b.dirty || b.conflict.value !== undefined) n++;
  unsaved.value = n;
}

/** The editor's text changed: save soon. */
export function edited(b: Buffer, text: string): void {
  b.text = text;
  countUnsaved();
  if (b.timer) clearTimeout(b.timer);
  b.timer = setTimeout(() => void save(b), SAVE_DELAY);
}

export async function save(b: Buffer): Promise<void> {
  if (b.timer) {
    clearTimeout(b.timer);
    b.timer = null;
  }
  if (b.conflict.value !== undefined || !b.dirty || b.inflight !== null) return;
  const text = b.text;
  b.inflight = text;
  const r = await post<Answer & { machine?: Full; disk?: string | null; conflict?: boolean; version?: string | null }>("/api/write", {
    machine: b.machine,
    file: b.file,
    text,
    base: b.version,
  });
  b.inflight = null;
  if (r.success) {
    b.base = text;
    if (r.machine) {
      b.version = r.machine.versions[b.file] ?? null;
      absorb(r.machine);
    }
  } else if (r.conflict) {
    b.conflictVersion = r.version ?? null;
    b.conflict.value = r.disk ?? null;
    say(r.message, false);
  } else {
    say(r.message, false);
  }
  countUnsaved();
  if (b.dirty && b.conflict.value === undefined) edited(b, b.text);
}

/** Save every file now (Ctrl+S). */
export async function saveAll(): Promise<void> {
  await Promise.all([...buffers.values()].map((b) => save(b)));
  say(unsaved.value ? "some files are not saved: see the conflicts" : "saved", !unsaved.value);
}

/** The conflict's choice: keep the page's text (written over the disk's) or take the disk's. */
export async function resolve(b: Buffer, keep: "mine" | "theirs"): Promise<void> {
  const disk = b.conflict.value;
  if (disk === undefined) return;
  const version = b.conflictVersion;
  b.conflict.value = undefined;
  if (keep === "theirs") {
    b.base = disk ?? "";
    b.version = version;
    b.replace(disk ?? "");
    countUnsaved();
  } else {
    b.base = disk ?? "";
    b.version = version;
    await save(b);
  }
}

/** A machine as the server sent it: kept, and every buffer of it brought up to date. */
export function absorb(full: Full): void {
  loaded.value = { ...loaded.value, [full.key]: full };
  for (const b of buffers.values()) {
    if (b.machine !== full.key) continue;
    const disk = full.files[b.file];
    const text = disk ?? "";
    const version = full.versions[b.file] ?? null;
    if (b.conflict.value !== undefined) {
      if (text === b.text) {
        b.conflict.value = undefined;
        b.base = text;
        b.version = version;
      } else {
        b.conflictVersion = version;
        b.conflict.value = disk ?? null;
      }
    } else if (text === b.text || text === b.inflight) {
      b.base = text;
      b.version = version;
    } else if (!b.dirty) {
      b.base = text;
      b.version = version;
      b.replace(text);
    } else if (version !== b.version) {
      b.conflictVersion = version; // changed on disk under unsaved edits: keep both
      b.conflict.value = disk ?? null;
    }
  }
  countUnsaved();
}

// -- requests ------------------------------------------------------------------------------------------

export function say(text: string, ok = true): void {
  status.value = { text, ok };
}

export async function open(key: string): Promise<void> {
  const r = await post<Answer & { machine?: Full }>("/api/machine", { machine: key });
  if (r.success && r.machine) {
    batch(() => {
      absorb(r.machine as Full);
      if (shown.value !== key) selection.value = null;
      shown.value = key;
    });
  } else say(r.message, false);
}

type Changing = Answer & { machine?: Full | null; key?: string };

function changedBy(r: Changing): boolean {
  if (r.machine) absorb(r.machine);
  say(r.message || (r.success ? "done" : "refused"), r.success);
  return r.success;
}

/** A structure operation of llfsm.edit on the shown machine (docs/edit.md lists them). */
export async function operate(op: string, args: Record<string, unknown>): Promise<boolean> {
  const key = shown.value;
  if (!key) return false;
  await saveAll();
  return changedBy(await post<Changing>("/api/op", { machine: key, op, args }));
}

export async function newMachine(name: string, states?: string[], folder = 0): Promise<boolean> {
  const r = await post<Changing>("/api/new", { name, folder, states: states?.length ? states : undefined });
  if (!changedBy(r)) return false;
  if (r.key) {
    shown.value = r.key;
    selection.value = null;
  }
  return true;
}

export async function undo(redo = false): Promise<void> {
  await saveAll();
  const r = await post<Changing>(redo ? "/api/redo" : "/api/undo", {});
  changedBy(r);
  if (r.key && r.machine) shown.value = r.key;
}

// -- what the server says --------------------------------------------------------------------------------

export function receive(m: Message): void {
  switch (m.type) {
    case "hello": {
      batch(() => {
        folders.value = m.folders as string[];
        machines.value = m.machines as Summary[];
        undoCount.value = Number(m.undo);
        redoCount.value = Number(m.redo);
        run.value = m.run as RunStatus;
      });
      const list = machines.value;
      if (!shown.value && list.length) void open(list[0].key);
      break;
    }
    case "changed": {
      batch(() => {
        machines.value = m.machines as Summary[];
        undoCount.value = Number(m.undo);
        redoCount.value = Number(m.redo);
      });
      const key = String(m.machine);
      if (key in loaded.value || key === shown.value) void open(key);
      if (m.origin === "disk") say(`${key}: ${(m.files as string[]).join(", ")} changed on disk`);
      break;
    }
    case "run":
      run.value = { ...(m as unknown as RunStatus) };
      if (m.state === "running") {
        live.value = NO_RUN;
        resetDebug();
      }
      break;
    case "output":
      run.value = { ...run.value, output: [...run.value.output.slice(-199), String(m.line)] };
      break;
    case "live":
      live.value = reduce(live.value, m.data as Record<string, unknown>);
      reduceDebug(m.data as Record<string, unknown>);
      break;
    case "bye":
      connection.value = "closed";
      break;
  }
}

export async function startRun(clock: string, nodes: string[], duration: number | null): Promise<void> {
  await saveAll();
  const r = await post("/api/run", { clock, nodes, duration });
  say(r.message, r.success);
}

export async function stopRun(): Promise<void> {
  const r = await post("/api/stop", {});
  say(r.message, r.success);
}

export async function command(machineName: string, verb: string): Promise<void> {
  const r = await post("/api/command", { machine: machineName, command: verb });
  say(r.message, r.success);
}
