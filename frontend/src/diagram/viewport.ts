// Zoom, pan and fit as arithmetic on the SVG's viewBox (the drawing itself is never redrawn
// for them, so they cost nothing on a big diagram).

export interface Box {
  x: number;
  y: number;
  w: number;
  h: number;
}

export const MIN_SCALE = 0.1;
export const MAX_SCALE = 8;

/** The viewBox showing all of `content` in a viewport of the given aspect, with a margin;
 * a small drawing is not blown up beyond `maxScale` (screen pixels per unit). */
export function fit(content: Box, width: number, height: number, margin = 12, maxScale = 1.25): Box {
  const cw = content.w + 2 * margin;
  const ch = content.h + 2 * margin;
  const aspect = width > 0 && height > 0 ? width / height : cw / ch;
  let w = cw;
  let h = ch;
  if (cw / ch < aspect) w = ch * aspect;
  else h = cw / aspect;
  if (width > 0 && width / w > maxScale) {
    w = width / maxScale;
    h = height / maxScale;
  }
  return { x: content.x - margin - (w - cw) / 2, y: content.y - margin - (h - ch) / 2, w, h };
}

/** Zoom by `factor` (> 1: closer) keeping the drawing's point (px, py) where it is on screen;
 * the scale stays within MIN_SCALE..MAX_SCALE of `base` (the fitted view). */
export function zoom(view: Box, factor: number, px: number, py: number, base: Box): Box {
  const scale = base.w / (view.w / factor);
  const clamped = Math.min(MAX_SCALE, Math.max(MIN_SCALE, scale));
  const w = base.w / clamped;
  const h = view.h * (w / view.w);
  return { x: px - ((px - view.x) * w) / view.w, y: py - ((py - view.y) * h) / view.h, w, h };
}

/** Move the view by (dx, dy) in the drawing's units (a drag to the right shows what is left). */
export function pan(view: Box, dx: number, dy: number): Box {
  return { ...view, x: view.x - dx, y: view.y - dy };
}

export function viewBox(b: Box): string {
  return `${b.x.toFixed(2)} ${b.y.toFixed(2)} ${b.w.toFixed(2)} ${b.h.toFixed(2)}`;
}

export function parseViewBox(text: string | null): Box | null {
  if (!text) return null;
  const v = text.trim().split(/[\s,]+/).map(Number);
  if (v.length !== 4 || v.some((n) => !Number.isFinite(n)) || v[2] <= 0 || v[3] <= 0) return null;
  return { x: v[0], y: v[1], w: v[2], h: v[3] };
}
