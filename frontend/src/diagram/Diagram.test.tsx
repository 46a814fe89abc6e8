import { render } from "preact";
import { act } from "preact/test-utils";
import { Diagram } from "./Diagram";

const SVG =
  '<svg xmlns="http://www.w3.org/2000/svg" class="diagram" data-machine="m" viewBox="0 0 200 100">' +
  '<g transform="translate(0 26)"><g class="edges"><path class="transition" data-machine="m" data-source="A" ' +
  'data-target="B" data-index="0" d="M0 0 L10 10"/></g><g class="states">' +
  '<g class="state" data-machine="m" data-state="A" aria-current="false"><rect x="0" y="0" width="90" height="34"/></g>' +
  '<g class="state" data-machine="m" data-state="B" aria-current="false"><rect x="100" y="50" width="90" height="34"/></g>' +
  "</g></g></svg>";

describe("the diagram on the page", () => {
  it("marks selection, the current state, problems and breakpoints through attributes", () => {
    const host = document.createElement("div");
    document.body.append(host);
    act(() =>
      render(
      <Diagram
        machine="m"
        svg={SVG}
        selected={{ transition: { source: "A", index: 0 } }}
        current="B"
        marks={new Map([["A", "error"]])}
        breakpoints={new Set(["B", "A#0"])}
      />,
      host,
    ));
    const a = host.querySelector<SVGGElement>('[data-state="A"]')!;
    const b = host.querySelector<SVGGElement>('[data-state="B"]')!;
    expect(a.getAttribute("aria-selected")).toBe("false");
    expect(a.dataset.problem).toBe("error");
    expect(b.getAttribute("aria-current")).toBe("true");
    expect(b.dataset.breakpoint).toBe("true");
    expect(a.getAttribute("tabindex")).toBe("0");
    const edge = host.querySelector<SVGElement>(".transition")!;
    expect(edge.dataset.selected).toBe("true");
    expect(edge.dataset.breakpoint).toBe("true");
    // a state selected instead: the edge is no longer
    act(() => render(<Diagram machine="m" svg={SVG} selected={{ state: "A" }} />, host));
    expect(a.getAttribute("aria-selected")).toBe("true");
    expect(edge.dataset.selected).toBeUndefined();
    expect(a.dataset.problem).toBeUndefined();
  });

  it("selects a state with the keyboard", () => {
    const host = document.createElement("div");
    document.body.append(host);
    const picked: unknown[] = [];
    act(() => render(<Diagram machine="m2" svg={SVG.replaceAll('"m"', '"m2"')} onSelect={(s) => picked.push(s)} />, host));
    const b = host.querySelector('[data-state="B"]')!;
    b.dispatchEvent(new KeyboardEvent("keydown", { key: "Enter", bubbles: true }));
    expect(picked).toEqual([{ state: "B" }]);
  });
});
