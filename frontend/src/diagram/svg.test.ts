import { parseSvg } from "./svg";

describe("a drawing from the server", () => {
  it("keeps the drawing's elements and drops scripts, handlers, links and styles", () => {
    const text =
      '<svg xmlns="http://www.w3.org/2000/svg" onload="alert(1)" viewBox="0 0 10 10">' +
      '<g class="state" data-state="A" onclick="alert(2)" style="fill:red"><rect x="0" y="0" width="5" height="5"/>' +
      '<text>A</text><script>alert(3)</script><a href="javascript:alert(4)"><text>x</text></a></g></svg>';
    const svg = parseSvg(text)!;
    expect(svg).not.toBeNull();
    expect(svg.getAttribute("onload")).toBeNull();
    const g = svg.querySelector("g")!;
    expect(g.getAttribute("onclick")).toBeNull();
    expect(g.getAttribute("style")).toBeNull();
    expect(svg.querySelector("script")).toBeNull();
    expect(svg.querySelector("a")).toBeNull();
    expect(g.getAttribute("data-state")).toBe("A");
  });

  it("refuses what is not SVG", () => {
    expect(parseSvg("<html><body>hi</body></html>")).toBeNull();
    expect(parseSvg("<svg><g></svg>")).toBeNull();
  });
});
