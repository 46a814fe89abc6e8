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

describe("the debugger's part of the channel", () => {
  it("is read from a hello's snapshot and from deltas (protocol 1), and gives each machine's values", () => {
    reduceDebug({
      type: "hello",
      protocol: 1,
      snapshot: { debug: { paused: true, where: "paused before the first round", breaks: ['state(ping) == "END"'], variables: { ping: { count: 2 } }, records: 5 } },
    });
    expect(debug.value.paused).toBe(true);
    expect(debug.value.records).toBe(5);
    expect(shownMachine("ping", "PUBLISH")).toEqual({ state: "PUBLISH", values: { count: 2 } });
    reduceDebug({ type: "delta", seq: 1, header: { t: 0.2 } });
    expect(debug.value.paused).toBe(true); // a delta without the part: the debugger did not change
    reduceDebug({ type: "delta", seq: 2, debug: { paused: false, where: "", breaks: [], variables: { ping: { count: 3 }, pong: { n: 1 } }, records: 6 } });
    expect(debug.value.paused).toBe(false);
    expect(shownMachine("ping", "WAIT")).toEqual({ state: "WAIT", values: { count: 3 } });
    // a delta names only the machines whose values changed; null: a machine gone
    reduceDebug({ type: "delta", seq: 3, debug: { paused: false, where: "", breaks: [], variables: { pong: { n: 2 } }, records: 7 } });
    expect(debug.value.variables).toEqual({ ping: { count: 3 }, pong: { n: 2 } });
    reduceDebug({ type: "delta", seq: 4, debug: { paused: false, where: "", breaks: [], variables: { ping: null }, records: 8 } });
    expect(debug.value.variables).toEqual({ pong: { n: 2 } });
    // a hello replaces them all
    reduceDebug({ type: "hello", protocol: 1, snapshot: { debug: { paused: false, variables: { ping: { count: 0 } }, records: 6 } } });
    expect(debug.value.variables).toEqual({ ping: { count: 0 } });
    reduceDebug({ type: "delta", seq: 5, debug: null });
    expect(debug.value.records).toBe(6); // a run without a debugger changes nothing
  });
});
