import { describe, expect, it } from "vitest";
import { breakExpression, debug, marksOf, reduceDebug, shownMachine } from "./store";

describe("breakpoints on the diagram", () => {
  it("are the expressions of a state and of a transition, and back", () => {
    const s = breakExpression("ping", { state: "PUBLISH" });
    const t = breakExpression("ping", { transition: { source: "WAIT", index: 1 } });
    expect(s).toBe('state(ping) == "PUBLISH"');
    expect(t).toBe('fired(ping, "WAIT", 1)');
    const marks = marksOf("ping", [s!, t!, 'state(other) == "A"', "ping.count > 3"]);
    expect([...marks].sort()).toEqual(["PUBLISH", "WAIT#1"]);
  });
});

describe("the debugger's part of a snapshot", () => {
  it("is read from hellos and snapshots alike, and gives each machine's values", () => {
    reduceDebug({
      type: "hello",
      snapshot: { debug: { paused: true, where: "paused before the first round", breaks: ['state(ping) == "END"'], variables: { ping: { count: 2 } }, records: 5 } },
    });
    expect(debug.value.paused).toBe(true);
    expect(debug.value.records).toBe(5);
    expect(shownMachine("ping", "PUBLISH")).toEqual({ state: "PUBLISH", values: { count: 2 } });
    reduceDebug({ type: "snapshot", debug: null });
    expect(debug.value.paused).toBe(true); // a snapshot without a debugger changes nothing
  });
});
