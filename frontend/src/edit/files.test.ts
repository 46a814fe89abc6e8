import { ownerOf, problemStates, stateLines } from "./files";

const states = ["INITIAL", "WAIT", "WAIT_Transition", "END"];

describe("files and the states they belong to", () => {
  it("finds a section's and a guard's state, the longest name first", () => {
    expect(ownerOf("State_WAIT_OnEntry.py", states)).toEqual({ state: "WAIT" });
    expect(ownerOf("State_WAIT_Transition_OnExit.py", states)).toEqual({ state: "WAIT_Transition" });
    expect(ownerOf("State_WAIT_Transition_1.expr", states)).toEqual({ state: "WAIT", transition: 1 });
    expect(ownerOf("State_WAIT_Variables.py", states)).toEqual({ state: "WAIT" });
    expect(ownerOf("Variables.py", states)).toBeNull();
    expect(ownerOf("State_GONE_OnEntry.py", states)).toBeNull();
  });

  it("marks each state with its worst problem, machine.yaml's by the state's lines", () => {
    const yaml = "initial: INITIAL\nstates:\n  - name: INITIAL\n    transitions: [WAIT]\n  - name: WAIT\n    transitions: [END]\n  - name: END\n";
    const lines = stateLines(yaml);
    expect(lines.get("WAIT")).toEqual([5, 6]);
    const d = (file: string, severity: string, line = 1) => ({ code: "LF000", severity, file, line, column: 1, message: "" });
    const marks = problemStates(
      [d("State_WAIT_OnEntry.py", "warning"), d("State_WAIT_Transition_0.expr", "error"), d("machine.yaml", "warning", 7)],
      states,
      lines,
    );
    expect(marks.get("WAIT")).toBe("error");
    expect(marks.get("END")).toBe("warning");
    expect(marks.has("INITIAL")).toBe(false);
  });
});
