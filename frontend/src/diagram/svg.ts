// The diagrams are drawn by the server (llfsm/diagram/svg.py: the one renderer, also behind
// `llfsm graph --format svg`); the page parses them as SVG, never as HTML, and keeps only the
// elements a drawing is made of, without event handlers, links or styles, so that a peer's
// text (`llfsm view` shows any DDS peer's machines) can never become markup or script here.

const SVG_ELEMENTS = new Set(["svg", "defs", "marker", "path", "g", "title", "rect", "text", "circle", "polygon",
  "ellipse"]);

export function parseSvg(text: string, doc: Document = document): SVGSVGElement | null {
  const parsed = new DOMParser().parseFromString(text, "image/svg+xml");
  const root = parsed.documentElement;
  if (root.nodeName !== "svg" || parsed.getElementsByTagName("parsererror").length) return null;
  for (const e of [...root.querySelectorAll("*")]) {
    if (!SVG_ELEMENTS.has(e.localName)) {
      e.remove();
      continue;
    }
    for (const a of [...e.attributes]) {
      if (a.name.startsWith("on") || a.localName === "href" || a.localName === "style") e.removeAttribute(a.name);
    }
  }
  for (const a of [...root.attributes]) {
    if (a.name.startsWith("on") || a.localName === "style") root.removeAttribute(a.name);
  }
  return doc.importNode(root, true) as unknown as SVGSVGElement;
}
