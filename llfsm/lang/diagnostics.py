"""Diagnostics: the stable rule catalogue and the four output formats of `llfsm check`.

Codes never change meaning once published: CI configurations and suppressions refer to them.
"""

from __future__ import annotations

import json
import os
import urllib.parse
from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path


class Severity(StrEnum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True)
class Rule:
    code: str
    severity: Severity
    name: str
    summary: str


def _r(code: str, sev: Severity, name: str, summary: str) -> Rule:
    return Rule(code, sev, name, summary)


E, W = Severity.ERROR, Severity.WARNING

#: Every rule llfsm checks.  docs/rules.md is written by hand, a section per rule of this table
#: (`### LFnnn name`); tests/test_check.py fails on a rule it does not document.
RULES: dict[str, Rule] = {
    r.code: r
    for r in [
        _r("LF001", E, "missing-machine-yaml", "The machine directory has no machine.yaml."),
        _r("LF002", E, "unreadable-file", "A file cannot be read as UTF-8 text within the size limit."),
        _r("LF003", E, "yaml-syntax", "machine.yaml is not valid YAML."),
        _r("LF004", E, "yaml-structure", "machine.yaml is not a mapping with a `states` list of the documented form."),
        _r("LF005", E, "yaml-alias", "machine.yaml uses anchors or aliases (refused: alias bombs)."),
        _r("LF006", E, "not-a-machine", "The path is not a machine directory."),
        _r("LF010", E, "invalid-machine-name", "The machine name is not an identifier, or is a Python keyword."),
        _r("LF011", E, "invalid-state-name", "A state name is not an identifier, or is a Python keyword."),
        _r("LF012", E, "duplicate-state", "Two states have the same name."),
        _r(
            "LF013",
            E,
            "reserved-name",
            "A name is reserved by llfsm (the machine's `self` at a section's level, the macros, `_llfsm*`).",
        ),
        _r("LF014", E, "name-too-long", "The machine name is too long for the file names a build writes."),
        _r("LF020", E, "unknown-target", "A transition names a state that does not exist."),
        _r("LF021", E, "unknown-initial", "`initial` names a state that does not exist."),
        _r("LF022", E, "unknown-suspended", "`suspended` names a state that does not exist."),
        _r("LF023", E, "missing-guard", "A transition has no guard: no State_S_Transition_N.expr file, none inline."),
        _r("LF024", E, "guard-not-expression", "A guard file is not exactly one Python expression."),
        _r("LF030", E, "syntax-error", "A code file is not valid Python."),
        _r("LF031", E, "includes-not-imports", "Includes.py holds something other than imports."),
        _r("LF032", E, "bad-variable", "A variables file holds something other than `name: type = value` lines."),
        _r("LF033", E, "shadowed-variable", "A state variable has the name of a machine variable."),
        _r("LF034", E, "global-nonlocal", "`global` or `nonlocal` in machine code."),
        _r("LF035", E, "duplicate-variable", "A variable is declared twice."),
        _r("LF036", E, "return-in-section", "`return`, `yield` or `await` at the top level of a section."),
        _r("LF038", E, "bad-binding", "A machine variable is bound by `:=`, import, def, class, except-as or match."),
        _r("LF037", E, "unsafe-path", "A file is a symlink leading out of the machine directory."),
        _r("LF040", E, "undeclared-name", "Code reads a name that nothing defines where it is read."),
        _r("LF041", E, "ros-habit", "An rclpy spelling llfsm does not take (rclpy, std_msgs.msg...)."),
        _r("LF039", E, "too-complex", "Code beyond a size or shape limit that keeps parsing it fast."),
        _r(
            "LF042",
            E,
            "unknown-interface-type",
            "An import of llfsm.msgs names a message, service or action type its package does not define.",
        ),
        _r(
            "LF043",
            E,
            "helper-inside-machine",
            "A helper module the code imports sits inside NAME.machine/, where imports do not look.",
        ),
        _r("LF046", E, "input-assigned", "Code assigns an input (or a part of one): inputs are read-only."),
        _r("LF047", E, "input-name", "An input's name is not usable or clashes with a variable."),
        _r("LF048", E, "input-value", "An input's type is unknown, or its default or domain holds a wrong value."),
        _r("LF049", E, "input-binding", "An input's topic, msg and field are incomplete, unknown or do not fit."),
        _r(
            "LF050",
            W,
            "unknown-machine",
            'suspend("M") and its family name a machine none of the machines checked (or beside them) is.',
        ),
        _r("LF051", E, "unknown-message-field", "Code uses a field that the message type of a variable does not have."),
        _r("LF060", E, "unknown-parameter", "`parameters:` names something that is not a machine variable."),
        _r(
            "LF061",
            E,
            "parameter-type",
            "A variable in `parameters:` is not annotated bool, int, float, str or list[...] of one of them.",
        ),
        _r("LF062", E, "duplicate-parameter", "`parameters:` names a variable twice."),
        _r("LF070", E, "guard-twice", "A guard is written inline in machine.yaml and in its .expr file too."),
        _r("LF071", W, "guard-comment", "A guard file's `# -> TARGET` names another target than its transition."),
        _r("LF072", W, "layout-unknown", "layout.yaml places a state or transition the machine does not have."),
        _r("LF073", E, "layout-invalid", "layout.yaml is not YAML of the documented form."),
        _r(
            "LF080",
            E,
            "untranslated-code",
            "A line of clfsm C++ that `llfsm import` left for a person to write in Python.",
        ),
        _r("LF101", W, "orphan-file", "A code file belongs to a state or transition that does not exist."),
        _r("LF102", W, "unreachable-state", "No path of transitions leads from the initial state to this state."),
        _r("LF103", W, "guard-always-false", "A guard is the constant False: the transition never fires."),
        _r("LF104", W, "unreachable-transition", "An earlier guard of the state is the constant True."),
        _r("LF105", W, "undefined-name", "A name nothing defines, unless a star import of Includes.py does."),
        _r("LF108", W, "semicolon", "A statement ends with `;`, a C++ habit Python does not need."),
        _r(
            "LF109",
            W,
            "unknown-interface-package",
            "An import of llfsm.msgs names a package found neither among llfsm's nor in the search path.",
        ),
        _r(
            "LF107",
            W,
            "suspend-state-code",
            "Transitions, Internal, OnExit or OnSuspend of the suspend state never run.",
        ),
        _r(
            "LF106",
            W,
            "undeclared-dependency",
            "Machine code imports messages of a package package.xml does not declare.",
        ),
        # `llfsm verify` only: code it cannot explore faithfully (never reported by check)
        _r("LF200", E, "unexplorable-code", "Code verify cannot explore faithfully (a read of the world)."),
        _r("LF201", E, "unexplorable-time", "An after* verify cannot follow (not a constant, or outside a state)."),
        _r("LF202", E, "input-without-domain", "An int, float or str input has no domain for verify to explore."),
        _r("LF203", E, "no-machine-source", "A built module whose machine directory verify cannot find."),
    ]
}


@dataclass(frozen=True)
class Diagnostic:
    code: str
    file: str
    line: int
    column: int
    message: str

    @property
    def severity(self) -> Severity:
        return RULES[self.code].severity

    @property
    def rule(self) -> Rule:
        return RULES[self.code]

    def sort_key(self) -> tuple[str, int, int, str, str]:
        return (self.file, self.line, self.column, self.code, self.message)

    def as_dict(self) -> dict[str, object]:
        return {
            "code": self.code,
            "severity": str(self.severity),
            "file": unicode_text(self.file),
            "line": self.line,
            "column": self.column,
            "message": self.message,
        }


def diag(code: str, file: str | Path, line: int, column: int, message: str) -> Diagnostic:
    """Build a diagnostic, keeping messages on one line whatever the input held."""
    if code not in RULES:
        raise KeyError(code)
    message = shown(" ".join(message.split()))
    return Diagnostic(code, str(file), max(line, 1), max(column, 1), message)


def shown(text: str) -> str:
    """`text` safe to print on a terminal or in a CI log.  File names come from untrusted pull
    requests: an escape sequence in one must not recolour, hide or forge output lines, and a
    name that is not UTF-8 must not make printing fail.  Control characters, lone surrogates
    and other unprintable characters are spelled out as Python escapes."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii") for ch in text)


def _path_bytes(path: str) -> bytes:
    """The bytes of a file name as the file system has them: a name that is not UTF-8 reaches
    Python with its bytes as lone surrogates (surrogateescape), and gets them back here."""
    try:
        return os.fsencode(path)
    except UnicodeEncodeError:  # a surrogate that no byte made (a name built in Python)
        return path.encode("utf-8", "surrogatepass")


def unicode_text(path: str) -> str:
    """`path` as valid Unicode for JSON: bytes that are not UTF-8 become `\\xNN` escapes
    instead of lone surrogates, which JSON parsers of other languages refuse."""
    try:
        path.encode("utf-8")
        return path
    except UnicodeEncodeError:
        return _path_bytes(path).decode("utf-8", "backslashreplace")


def file_uri(path: str) -> str:
    """An RFC 3986 reference for a file name, as SARIF's `artifactLocation.uri` requires.

    Every byte but unreserved characters and `/` is percent-encoded (UTF-8 for text, the raw
    byte for a name that is not UTF-8), so `#`, `?`, `%`, spaces and a `:` that would read as
    a scheme all stay part of the path.  A relative name stays a relative reference (to the
    folder `llfsm check` ran in); an absolute one becomes a `file:` URI."""
    raw = _path_bytes(path)
    quoted = urllib.parse.quote(raw, safe="/")
    if raw.startswith(b"/"):
        return "file://" + ("/" + quoted.lstrip("/") if raw.startswith(b"//") else quoted)
    return quoted


FORMATS = ("text", "json", "github", "sarif")


def format_text(diags: Iterable[Diagnostic]) -> str:
    return "".join(f"{shown(d.file)}:{d.line}:{d.column}: {d.code} {d.severity}: {d.message}\n" for d in diags)


def format_json(diags: Iterable[Diagnostic]) -> str:
    return json.dumps([d.as_dict() for d in diags], indent=2) + "\n"


def _gh_escape(value: str, prop: bool = False) -> str:
    value = value.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    if prop:
        value = value.replace(":", "%3A").replace(",", "%2C")
    return value


def format_github(diags: Iterable[Diagnostic]) -> str:
    """GitHub Actions workflow commands: each diagnostic becomes an annotation on the PR."""
    out = []
    for d in diags:
        kind = "error" if d.severity is Severity.ERROR else "warning"
        out.append(
            f"::{kind} file={_gh_escape(shown(d.file), True)},line={d.line},col={d.column},"
            f"title={_gh_escape(d.code, True)}::{_gh_escape(d.message)}\n"
        )
    return "".join(out)


def format_sarif(diags: Iterable[Diagnostic], version: str) -> str:
    diags = list(diags)
    used = sorted({d.code for d in diags})
    rules = [
        {
            "id": code,
            "name": RULES[code].name,
            "shortDescription": {"text": RULES[code].summary},
            "defaultConfiguration": {"level": str(RULES[code].severity)},
            "helpUri": f"https://llfsm.invalid/docs/rules#{code.lower()}",
        }
        for code in used
    ]
    results = [
        {
            "ruleId": d.code,
            "ruleIndex": used.index(d.code),
            "level": str(d.severity),
            "message": {"text": d.message},
            "locations": [
                {
                    "physicalLocation": {
                        "artifactLocation": {"uri": file_uri(Path(d.file).as_posix())},
                        "region": {"startLine": d.line, "startColumn": d.column},
                    }
                }
            ],
        }
        for d in diags
    ]
    doc = {
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "llfsm",
                        "version": version,
                        "informationUri": "https://llfsm.invalid/",
                        "rules": rules,
                    }
                },
                "results": results,
            }
        ],
    }
    return json.dumps(doc, indent=2) + "\n"


def render(diags: Iterable[Diagnostic], fmt: str, version: str) -> str:
    if fmt == "text":
        return format_text(diags)
    if fmt == "json":
        return format_json(diags)
    if fmt == "github":
        return format_github(diags)
    if fmt == "sarif":
        return format_sarif(diags, version)
    raise ValueError(fmt)
