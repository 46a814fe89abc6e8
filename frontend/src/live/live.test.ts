import { NO_RUN, reduce } from "./live";

describe("the live view's messages", () => {
  it("take each machine's state and status from hello and snapshots", () => {
    const hello = { type: "hello", machines: [], snapshot: { t: 0.5, clock: "sim", machines: [{ name: "pp", state: "INITIAL", status: "running", since: 0 }] } };
    let live = reduce(NO_RUN, hello);
    expect(live.machines.pp.state).toBe("INITIAL");
    live = reduce(live, { type: "snapshot", t: 1.0, clock: "sim", ended: true, machines: [{ name: "pp", state: "END", status: "finished", since: 0.2, pending: "" }] });
    expect(live).toMatchObject({ t: 1.0, ended: true, machines: { pp: { state: "END", status: "finished", pending: null } } });
    expect(reduce(live, { type: "graph" })).toBe(live);
  });
});
