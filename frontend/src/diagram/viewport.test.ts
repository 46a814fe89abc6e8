import { fit, MAX_SCALE, pan, parseViewBox, viewBox, zoom } from "./viewport";

describe("viewport", () => {
  const content = { x: 0, y: 0, w: 400, h: 200 };

  it("fits the whole drawing with its margin, centred, in the viewport's aspect", () => {
    const v = fit(content, 420, 420, 10);
    expect(v.w).toBeCloseTo(420);
    expect(v.h).toBeCloseTo(420); // square viewport: the height grows
    expect(v.x).toBeCloseTo(-10);
    expect(v.y + v.h / 2).toBeCloseTo(100); // centred on the drawing
  });

  it("does not blow a small drawing up", () => {
    const v = fit(content, 2000, 1000, 0, 1.25);
    expect(v.w).toBeCloseTo(1600);
    expect(v.x + v.w / 2).toBeCloseTo(200);
  });

  it("zooms around the pointer: that point stays put", () => {
    const base = fit(content, 400, 200, 0);
    const z = zoom(base, 2, 100, 50, base);
    expect(z.w).toBeCloseTo(base.w / 2);
    // the point's place within the view is the same fraction before and after
    expect((100 - z.x) / z.w).toBeCloseTo((100 - base.x) / base.w);
    expect((50 - z.y) / z.h).toBeCloseTo((50 - base.y) / base.h);
  });

  it("never zooms in past MAX_SCALE", () => {
    const base = fit(content, 400, 200, 0);
    let v = base;
    for (let i = 0; i < 50; i++) v = zoom(v, 2, 200, 100, base);
    expect(base.w / v.w).toBeCloseTo(MAX_SCALE);
  });

  it("pans against the drag and round-trips through the attribute", () => {
    const v = pan({ x: 0, y: 0, w: 10, h: 10 }, 3, -2);
    expect(v).toEqual({ x: -3, y: 2, w: 10, h: 10 });
    expect(parseViewBox(viewBox(v))).toEqual(v);
    expect(parseViewBox("0 0 0 10")).toBeNull();
    expect(parseViewBox("a b c d")).toBeNull();
  });
});
