// One machine's diagram as the server drew it, made interactive: selection (pointer and
// keyboard), dragging a state (the editor), zoom, pan and fit, and the marks other parts of
// the application put on it through attributes: the live view's current state
// (`aria-current`), the editor's problems (`data-problem`), the debugger's breakpoints
// (`data-breakpoint`).  The drawing itself is never changed here but for those attributes and
// a dragged state's transform: a new drawing comes from the server.

import { useEffect, useRef } from "preact/hooks";
import { parseSvg } from "./svg";
import { type Box, fit, pan, parseViewBox, viewBox, zoom } from "./viewport";

export interface Selection {
  state?: string;
  transition?: { source: string; index: number };
}

export interface DiagramProps {
  machine: string;
  svg: string;
  selected?: Selection | null;
  /** The live view's current state. */
  current?: string | null;
  /** Problem states: name -> the worst severity. */
  marks?: ReadonlyMap<string, string>;
  /** The debugger's breakpoints: state names, and transitions as "SOURCE#INDEX". */
  breakpoints?: ReadonlySet<string>;
  /** States may be dragged (the editor): the new centres when one is dropped. */
  onMove?: (positions: Record<string, [number, number]>) => void;
  /** A transition's label dragged (the editor): its new top-left corner. */
  onMoveLabel?: (transition: { source: string; index: number }, corner: [number, number]) => void;
  onSelect?: (sel: Selection) => void;
  /** The debugger: a breakpoint toggled on a state or a transition (Alt+click, or B on it). */
  onToggleBreakpoint?: (sel: Selection) => void;
  label?: string;
}

/** Where each diagram was zoomed and panned to, kept across redraws (per machine). */
const views = new Map<string, Box>();
const DRAG_THRESHOLD = 4;
const ARROWS: Record<string, [number, number]> = {
  ArrowLeft: [-1, 0],
  ArrowRight: [1, 0],
  ArrowUp: [0, -1],
  ArrowDown: [0, 1],
};

export function Diagram(props: DiagramProps) {
  const box = useRef<HTMLDivElement>(null);
  const latest = useRef(props);
  latest.current = props;

  // a new drawing: parse it, keep the view the user had
  useEffect(() => {
    const host = box.current;
    if (!host) return;
    const svg = parseSvg(props.svg);
    if (!svg) {
      host.replaceChildren(document.createTextNode("(this diagram cannot be drawn)"));
      return;
    }
    const content = parseViewBox(svg.getAttribute("viewBox")) ?? { x: 0, y: 0, w: 400, h: 300 };
    svg.dataset.content = viewBox(content);
    svg.removeAttribute("width");
    svg.removeAttribute("height");
    svg.setAttribute("role", "listbox");
    svg.setAttribute("aria-label", props.label ?? `states of ${props.machine}`);
    for (const g of svg.querySelectorAll<SVGGElement>(".state")) {
      g.setAttribute("tabindex", "0");
      g.setAttribute("role", "option");
      g.setAttribute("aria-selected", "false");
    }
    host.replaceChildren(svg);
    const kept = views.get(props.machine);
    setView(svg, kept ?? fitted(svg, host));
    decorate(svg, props);
  }, [props.svg, props.machine]);

  // marks and selection: attributes only
  useEffect(() => {
    const svg = box.current?.querySelector("svg");
    if (svg) decorate(svg, props);
  });

  useEffect(() => {
    const host = box.current;
    if (!host) return;
    return attach(host, latest);
  }, []);

  return <div class="diagram-box" ref={box} />;
}

function fitted(svg: SVGSVGElement, host: HTMLElement): Box {
  const content = parseViewBox(svg.dataset.content ?? null) ?? { x: 0, y: 0, w: 400, h: 300 };
  return fit(content, host.clientWidth, host.clientHeight);
}

function setView(svg: SVGSVGElement, b: Box): void {
  svg.setAttribute("viewBox", viewBox(b));
  const machine = svg.dataset.machine;
  if (machine) views.set(machine, b);
}

function decorate(svg: SVGSVGElement, p: DiagramProps): void {
  for (const g of svg.querySelectorAll<SVGGElement>(".state")) {
    const name = g.dataset.state ?? "";
    g.setAttribute("aria-selected", String(p.selected?.state === name));
    g.setAttribute("aria-current", String(p.current === name));
    const mark = p.marks?.get(name);
    if (mark) g.dataset.problem = mark;
    else delete g.dataset.problem;
    if (p.breakpoints?.has(name)) g.dataset.breakpoint = "true";
    else delete g.dataset.breakpoint;
  }
  const t = p.selected?.transition;
  for (const e of svg.querySelectorAll<SVGElement>(".transition[data-index], .guard[data-index]")) {
    const key = `${e.dataset.source}#${e.dataset.index}`;
    const on = !!t && e.dataset.source === t.source && e.dataset.index === String(t.index);
    if (on) e.dataset.selected = "true";
    else delete e.dataset.selected;
    if (p.breakpoints?.has(key)) e.dataset.breakpoint = "true";
    else delete e.dataset.breakpoint;
  }
}

/** What a pointer or key on the drawing means; the handlers read the latest props. */
function attach(host: HTMLElement, latest: { current: DiagramProps }): () => void {
  let drag: { g: SVGGElement; x0: number; y0: number; moved: boolean; ctm: DOMMatrix; id: number } | null = null;
  let dragged = false; // the click that ends a drag selects nothing
  let panning: { x: number; y: number; view: Box; id: number } | null = null;

  const svgOf = () => host.querySelector("svg");
  const target = (e: Event) => {
    const el = e.target as Element | null;
    return {
      state: el?.closest?.(".state") as SVGGElement | null,
      edge: el?.closest?.(".transition[data-index], .guard[data-index]") as SVGElement | null,
    };
  };
  const picked = (state: SVGGElement | null, edge: SVGElement | null): Selection | null => {
    if (state?.dataset.state) return { state: state.dataset.state };
    if (edge?.dataset.source) return { transition: { source: edge.dataset.source, index: Number(edge.dataset.index) } };
    return null;
  };
  const select = (state: SVGGElement | null, edge: SVGElement | null, toggle = false) => {
    const p = latest.current;
    const sel = picked(state, edge);
    if (!sel) return;
    if (toggle && p.onToggleBreakpoint) p.onToggleBreakpoint(sel);
    else p.onSelect?.(sel);
  };

  const down = (e: PointerEvent) => {
    const svg = svgOf();
    if (!svg || e.button !== 0) return;
    const { state, edge } = target(e);
    const label = edge?.classList.contains("guard") && latest.current.onMoveLabel ? (edge as SVGGElement) : null;
    const movable = state && latest.current.onMove ? state : label;
    dragged = false;
    if (movable) {
      const ctm = (movable.parentNode as SVGGraphicsElement).getScreenCTM();
      if (!ctm) return;
      drag = { g: movable, x0: e.clientX, y0: e.clientY, moved: false, ctm: ctm.inverse(), id: e.pointerId };
      host.setPointerCapture?.(e.pointerId);
      e.preventDefault();
    } else if (!state && !edge) {
      const view = parseViewBox(svg.getAttribute("viewBox"));
      if (view) panning = { x: e.clientX, y: e.clientY, view, id: e.pointerId };
      host.setPointerCapture?.(e.pointerId);
    }
  };
  const move = (e: PointerEvent) => {
    if (drag && e.pointerId === drag.id) {
      const dxs = e.clientX - drag.x0;
      const dys = e.clientY - drag.y0;
      if (!drag.moved && Math.hypot(dxs, dys) < DRAG_THRESHOLD) return;
      drag.moved = true;
      const d = delta(drag.ctm, dxs, dys);
      drag.g.setAttribute("transform", `translate(${d.x.toFixed(1)} ${d.y.toFixed(1)})`);
      drag.g.dataset.dragging = "true";
    } else if (panning && e.pointerId === panning.id) {
      const svg = svgOf();
      if (!svg) return;
      const scale = panning.view.w / Math.max(1, host.clientWidth);
      setView(svg, pan(panning.view, (e.clientX - panning.x) * scale, (e.clientY - panning.y) * scale));
    }
  };
  const up = (e: PointerEvent) => {
    if (drag && e.pointerId === drag.id) {
      const { g, moved } = drag;
      const isState = g.classList.contains("state");
      if (moved) {
        const d = delta(drag.ctm, e.clientX - drag.x0, e.clientY - drag.y0);
        if (isState) {
          const c = centre(g);
          latest.current.onMove?.({ [g.dataset.state ?? ""]: [round(c.x + d.x), round(c.y + d.y)] });
        } else {
          const r = g.querySelector("rect");
          const at = (a: string) => Number(r?.getAttribute(a) ?? 0);
          latest.current.onMoveLabel?.(
            { source: g.dataset.source ?? "", index: Number(g.dataset.index) },
            [round(at("x") + d.x), round(at("y") + d.y)],
          );
        }
        dragged = true;
      } else {
        select(isState ? g : null, isState ? null : g, e.altKey);
        dragged = true;
      }
      drag = null;
    } else if (panning && e.pointerId === panning.id) {
      panning = null;
    }
  };
  const click = (e: MouseEvent) => {
    if (dragged) {
      dragged = false;
      return;
    }
    const { state, edge } = target(e);
    if (!state && edge) select(null, edge, e.altKey);
    else if (state && !latest.current.onMove) select(state, null, e.altKey);
  };
  const key = (e: KeyboardEvent) => {
    const { state, edge } = target(e);
    if ((e.key === "Enter" || e.key === " ") && (state || edge)) {
      e.preventDefault();
      select(state, edge);
    } else if ((e.key === "b" || e.key === "B") && (state || edge) && latest.current.onToggleBreakpoint) {
      e.preventDefault();
      select(state, edge, true);
    }
    // Alt+arrows move the focused state (Shift: further): a layout without a pointer
    const step = ARROWS[e.key];
    if (step && e.altKey && state && latest.current.onMove) {
      e.preventDefault();
      const c = centre(state);
      const k = e.shiftKey ? 50 : 10;
      latest.current.onMove({ [state.dataset.state ?? ""]: [round(c.x + step[0] * k), round(c.y + step[1] * k)] });
    }
  };
  const wheel = (e: WheelEvent) => {
    const svg = svgOf();
    const view = svg && parseViewBox(svg.getAttribute("viewBox"));
    if (!svg || !view) return;
    e.preventDefault();
    const r = host.getBoundingClientRect();
    const px = view.x + ((e.clientX - r.left) / Math.max(1, r.width)) * view.w;
    const py = view.y + ((e.clientY - r.top) / Math.max(1, r.height)) * view.h;
    setView(svg, zoom(view, e.deltaY < 0 ? 1.15 : 1 / 1.15, px, py, fitted(svg, host)));
  };
  const listeners: [string, EventListener, AddEventListenerOptions?][] = [
    ["pointerdown", down as EventListener],
    ["pointermove", move as EventListener],
    ["pointerup", up as EventListener],
    ["pointercancel", up as EventListener],
    ["click", click as EventListener],
    ["keydown", key as EventListener],
    ["wheel", wheel as EventListener, { passive: false }],
  ];
  for (const [type, fn, options] of listeners) host.addEventListener(type, fn, options);
  return () => {
    for (const [type, fn] of listeners) host.removeEventListener(type, fn);
  };
}

function delta(inverse: DOMMatrix, dx: number, dy: number): { x: number; y: number } {
  // a screen offset in the drawing's units (the inverse's linear part alone)
  return { x: inverse.a * dx + inverse.c * dy, y: inverse.b * dx + inverse.d * dy };
}

function centre(g: SVGGElement): { x: number; y: number } {
  const r = g.querySelector("rect");
  const n = (a: string) => Number(r?.getAttribute(a) ?? 0);
  return { x: n("x") + n("width") / 2, y: n("y") + n("height") / 2 };
}

function round(v: number): number {
  return Math.round(v * 10) / 10;
}

/** The buttons beside a diagram: zoom in and out around the middle, and fit. */
export function zoomDiagram(machine: string, how: "in" | "out" | "fit"): void {
  const svg = document.querySelector<SVGSVGElement>(`.diagram-box svg[data-machine="${CSS.escape(machine)}"]`);
  const host = svg?.parentElement;
  if (!svg || !host) return;
  const base = fitted(svg, host);
  const view = parseViewBox(svg.getAttribute("viewBox")) ?? base;
  if (how === "fit") setView(svg, base);
  else setView(svg, zoom(view, how === "in" ? 1.25 : 0.8, view.x + view.w / 2, view.y + view.h / 2, base));
}
