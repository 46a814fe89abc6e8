import { absorb, buffer, type Full } from "./store";

function full(files: Record<string, string>, versions: Record<string, string>): Full {
  return { key: "m", name: "m", folder: "/x", files, versions, diagnostics: [], structure: null, svg: "", stale: false };
}

describe("buffers against the disk", () => {
  it("take a change on disk when they hold no edits, and keep both when they do", () => {
    absorb(full({ "Variables.py": "a: int = 0\n" }, { "Variables.py": "v1" }));
    const b = buffer("m", "Variables.py");
    expect(b.text).toBe("a: int = 0\n");
    // another program writes the file: a clean buffer follows it
    absorb(full({ "Variables.py": "a: int = 1\n" }, { "Variables.py": "v2" }));
    expect(b.text).toBe("a: int = 1\n");
    expect(b.external.value.text).toBe("a: int = 1\n");
    expect(b.conflict.value).toBeUndefined();
    // the user types (not saved yet), and the disk changes again: a conflict keeps both
    b.text = "a: int = 5\n";
    absorb(full({ "Variables.py": "a: int = 9\n" }, { "Variables.py": "v3" }));
    expect(b.text).toBe("a: int = 5\n");
    expect(b.conflict.value).toBe("a: int = 9\n");
  });

  it("take their own save landing as the disk's version, not as a conflict", () => {
    absorb(full({ "Includes.py": "" }, { "Includes.py": "i1" }));
    const b = buffer("m", "Includes.py");
    b.text = "import math\nimport os\n";
    b.inflight = "import math\n"; // saved while the user went on typing
    absorb(full({ "Includes.py": "import math\n" }, { "Includes.py": "i2" }));
    expect(b.conflict.value).toBeUndefined();
    expect(b.base).toBe("import math\n");
    expect(b.version).toBe("i2");
    expect(b.text).toBe("import math\nimport os\n");
  });
});
