import { NO_RUN, PROTOCOL, reduce } from "./live";

describe("the live view's messages (protocol 1)", () => {
  it("take each machine's state and status from the hello, then from the deltas that name it", () => {
    const pp = { name: "pp", state: "INITIAL", status: "running", since: 0 };
    const hello = {
      type: "hello",
      protocol: PROTOCOL,
      machines: [],
      snapshot: { type: "delta", seq: 0, header: { t: 0.5, clock: "sim", ended: false }, machines: { upsert: [pp], remove: [] } },
    };
    let live = reduce(NO_RUN, hello);
    expect(live).toMatchObject({ t: 0.5, clock: "sim", machines: { pp: { state: "INITIAL" } } });
    live = reduce(live, { type: "delta", seq: 1, header: { t: 1.0, clock: "sim", ended: true },
      machines: { upsert: [{ name: "pp", state: "END", status: "finished", since: 0.2, pending: "" }], remove: [] } });
    expect(live).toMatchObject({ t: 1.0, ended: true, machines: { pp: { state: "END", status: "finished", pending: null } } });
    // a delta that names nothing of the machines leaves them as they were; one that removes one drops it
    expect(reduce(live, { type: "delta", seq: 2, header: { t: 1.5 } }).machines.pp.state).toBe("END");
    expect(reduce(live, { type: "delta", seq: 2, machines: { upsert: [], remove: ["pp"] } }).machines).toEqual({});
    expect(reduce(live, { type: "graph" })).toBe(live);
  });

  it("a hello of another protocol changes nothing", () => {
    expect(reduce(NO_RUN, { type: "hello", protocol: PROTOCOL + 1, snapshot: {} })).toBe(NO_RUN);
  });
});
