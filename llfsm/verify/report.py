"""What `llfsm verify` prints: a line per property, counterexamples as clfsm's `-v` trace, in
the four formats of `llfsm check` (text, json, github, sarif; docs/verify.md, "Output").

A counterexample lists each ringlet of the path: clfsm's `-v` line (`m%3d s%3d - name - STATE`)
before a ringlet that enters a state, then what the ringlet did, with the values of the
machine's inputs, the time it took to have passed in its state, the variables that changed and
the topics published.  A lasso marks where its loop starts and ends.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..lang.diagnostics import file_uri, shown
from .explorer import TURN, Explorer, Step
from .judge import Outcome, Trace, Verification
from .memory import size_text
from .values import shown as value_text


def _counts(v: Verification) -> str:
    return f"{v.configurations:,} configurations, {v.steps:,} steps"


def _line(o: Outcome, v: Verification) -> str:
    verdict = o.verdict if o.verdict != "unknown" else f"unknown ({o.why})"
    return f"{o.prop.name}: {verdict} ({_counts(v)}, {o.seconds:.2f} s)"


def step_lines(e: Explorer, step: Step | None, config: tuple[Any, ...]) -> list[str]:
    """A step as lines of text (indented by the caller)."""
    if step is None:
        return ["(the run has ended: every machine finished or suspended; it stays so)"] if config[TURN] < 0 else []
    out = []
    m = e.machines[step.machine]
    for kind, k, state in step.commands:
        target = e.machines[k]
        out.append(f"{target.NAME}: {kind} applied -> {target.STATES[state]}")
    for k, state in step.entered:
        mk = e.machines[k]
        out.append("m%3d s%3d - %-20.20s - %s" % (k, state, mk.NAME, mk.STATES[state]))  # noqa: UP031 (clfsm format)
    what = []
    if step.inputs:
        what.append("inputs " + ", ".join(f"{n}={value_text(v)}" for n, v in step.inputs.items()))
    if step.interval:
        what.append(f"time {step.interval}")
    if step.interrupted:
        what.append("interrupted: ros.ok() is false from here")
    part = e.part(config, step.machine)
    if step.finished:
        done = "finished"
    elif step.transition is not None:
        done = f"transition {step.transition} of {m.STATES[step.state]} fired -> {m.STATES[part[2]]}"
    else:
        done = "no transition"
    out.append(f"[round {step.round}] {m.NAME}: {done}" + (f" ({'; '.join(what)})" if what else ""))
    for said in step.environment:
        out.append(f"    environment: {said}")
    for name, (old, new) in step.changed.items():
        out.append(f"    {name}: {value_text(old)} -> {value_text(new)}")
    if step.published:
        out.append(f"    published {', '.join(sorted(step.published))}")
    return out


#: A run of more quiet ringlets than this is shown as its first two and last two: a path in
#: exact time (`--period 1ms`) waits a thousand rounds for `after(1)`, and a reader wants the
#: rounds in which something happened.
FOLD = 6


def _quiet(steps: list[tuple[tuple[Any, ...], Step | None]]) -> list[bool]:
    """Per step: a ringlet that fired nothing, entered nothing, changed and published nothing,
    and read the inputs its machine read in its ringlet before (a machine with inputs reads
    them in every ringlet: waiting for `after_ms(300)` with the sensor clear is idle too)."""
    out = []
    last: dict[int, dict[str, Any]] = {}  # machine -> the inputs of its latest ringlet
    for _config, step in steps:
        if step is None:
            out.append(False)
            continue
        same_inputs = not step.inputs or last.get(step.machine) == step.inputs
        last[step.machine] = step.inputs
        out.append(
            same_inputs
            and step.transition is None
            and not (step.finished or step.commands or step.entered or step.changed)
            and not (step.published or step.interrupted)
        )
    return out


def trace_lines(e: Explorer, trace: Trace, what: str = "counterexample") -> list[str]:
    steps = trace.steps
    n = len(steps) - 1
    head = f"{what}, {n} step{'s' if n != 1 else ''}"
    if trace.loop is not None:
        k = n - trace.loop
        last = "the last step repeats" if k == 1 else f"the last {k} steps repeat"
        head += f" (a lasso: {last} forever)"
    out = [head + ":"]
    loop_start = None if trace.loop is None else trace.loop + 1

    def show(k: int) -> None:
        config, step = steps[k]
        out.extend("  " + line for line in step_lines(e, step, config))

    quiet = _quiet(steps)
    pos = 0
    while pos < len(steps):
        if pos == loop_start:
            out.append("  -- the loop starts here --")
        end = pos  # the last of a run of quiet ringlets starting here (never across the loop's start)
        while quiet[pos] and end + 1 < len(steps) and end + 1 != loop_start and quiet[end + 1]:
            end += 1
        if end - pos + 1 <= FOLD:
            show(pos)
            pos += 1
            continue
        folded_from, folded_to = steps[pos + 2][1], steps[end - 2][1]
        assert folded_from is not None and folded_to is not None
        show(pos)
        show(pos + 1)
        out.append(
            f"  ... {end - pos - 3:,} more ringlets in which nothing fired, changed or was published"
            f"{', the inputs as before' if folded_from.inputs else ''} "
            f"(rounds {folded_from.round}-{folded_to.round}; --format json lists each) ..."
        )
        show(end - 1)
        show(end)
        pos = end + 1
    if trace.loop is not None:
        out.append("  -- and back to where the loop starts --")
    final = steps[-1][0]
    states = []
    for k, m in enumerate(e.machines):
        part = e.part(final, k)
        status = " (finished)" if part[6] else " (suspended)" if part[4] else ""
        states.append(f"{m.NAME} {m.STATES[part[2]]}{status}")
    out.append(f"  then: {', '.join(states)}")
    return out


def text(v: Verification, witnesses: bool = False) -> str:
    """The report; `witnesses`: also the path to what a `reachable` or `EF` property found."""
    lines = []
    for o in v.outcomes:
        lines.append(_line(o, v))
        if o.trace is not None and v.explorer is not None and (o.verdict != "holds" or witnesses):
            kind = "witness" if o.verdict == "holds" else "counterexample"
            lines += ["  " + x for x in trace_lines(v.explorer, o.trace, kind)]
        elif o.verdict == "fails" and o.why:
            lines.append(f"  ({o.why})")
    if v.error is not None:
        lines.append("machine code raised while exploring:")
        lines += ["  " + x for x in v.error.rstrip("\n").split("\n")]
        if v.error_trace is not None and v.explorer is not None and v.error_trace.steps:
            lines += ["  " + x for x in trace_lines(v.explorer, v.error_trace, "the path to it")]
    if v.partial == "state limit":
        lines.append(
            f"stopped at the state limit ({v.configurations:,} configurations; --max-states raises it)"
            + (": the variables that kept growing: " + "; ".join(v.growing) if v.growing else "")
        )
    elif v.partial == "memory bound" and v.memory is not None:
        used, bound = v.memory
        lines.append(
            f"stopped at the memory bound ({size_text(used)} in use, --max-memory {size_text(bound)}; "
            f"{v.configurations:,} configurations; --max-memory raises it)"
            + (": the variables that grew: " + "; ".join(v.growing) if v.growing else "")
        )
    elif v.partial == "interrupted":
        lines.append(f"interrupted: a partial result ({v.configurations:,} configurations explored so far)")
    if v.loaded.bounds:
        shown_bounds = ", ".join(f"{k} <= {b:g}" for k, b in v.loaded.bounds.items())
        lines.append(
            f"bounded: {shown_bounds} ({v.cut:,} configurations past a bound were not explored further): "
            "the verdicts hold for the runs within these bounds"
        )
    if v.hint is not None:
        lines.append(v.hint)
    for w in v.warnings:
        lines.append(f"warning: {w}")
    if not v.outcomes and v.error is None:
        lines.append(f"explored {_counts(v)} in {v.seconds:.2f} s (no property given)")
    return "\n".join(lines) + "\n"


def _trace_json(e: Explorer, trace: Trace) -> dict[str, Any]:
    steps: list[dict[str, Any]] = []
    for config, step in trace.steps[1:]:
        if step is None:
            steps.append({"ended": True})
            continue
        m = e.machines[step.machine]
        part = e.part(config, step.machine)
        steps.append(
            {
                "round": step.round,
                "machine": m.NAME,
                "id": step.machine,
                "entered": [{"machine": e.machines[k].NAME, "state": e.machines[k].STATES[s]} for k, s in step.entered],
                "commands": [
                    {"command": c, "machine": e.machines[k].NAME, "state": e.machines[k].STATES[s]}
                    for c, k, s in step.commands
                ],
                "inputs": {n: _plain(x) for n, x in step.inputs.items()},
                "time": step.interval,
                "interrupted": step.interrupted,
                "transition": step.transition,
                "state": m.STATES[part[2]],
                "changed": {n: [value_text(a), value_text(b)] for n, (a, b) in step.changed.items()},
                "published": sorted(step.published),
                "environment": step.environment,
            }
        )
    return {"steps": steps, "loop": trace.loop}


def _plain(x: Any) -> Any:
    return x if isinstance(x, bool | int | float | str) or x is None else value_text(x)


def as_json(v: Verification) -> str:
    doc: dict[str, Any] = {
        "machines": [c.NAME for c in v.loaded.classes],
        "configurations": v.configurations,
        "steps": v.steps,
        "seconds": round(v.seconds, 3),
        "partial": v.partial,
        "growing": v.growing,
        "properties": [],
        "error": v.error,
        "warnings": v.warnings,
        "bounds": v.loaded.bounds,
        "cut": v.cut,
    }
    for o in v.outcomes:
        item: dict[str, Any] = {
            "name": o.prop.name,
            "kind": o.prop.kind,
            "text": o.prop.text,
            "where": o.prop.where,
            "verdict": o.verdict,
            "seconds": round(o.seconds, 3),
        }
        if o.why:
            item["why"] = o.why
        if o.trace is not None and v.explorer is not None:
            item["witness" if o.verdict == "holds" else "counterexample"] = _trace_json(v.explorer, o.trace)
        doc["properties"].append(item)
    return json.dumps(doc, indent=2) + "\n"


def _location(o: Outcome, v: Verification) -> tuple[str, int]:
    """Where a property is written: its line of the verification file, or the first machine's
    machine.yaml for one given with --property."""
    where = o.prop.where
    file, _, line = where.rpartition(":")
    if file and line.isdigit():
        return file, int(line)
    return str(Path(v.loaded.paths[0]) / "machine.yaml") if v.loaded.paths else "machine.yaml", 1


def _gh(value: str, prop: bool = False) -> str:
    value = value.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    return value.replace(":", "%3A").replace(",", "%2C") if prop else value


def github(v: Verification) -> str:
    out = []
    for o in v.outcomes:
        if o.verdict == "holds":
            continue
        file, line = _location(o, v)
        kind = "error" if o.verdict == "fails" else "warning"
        detail = _line(o, v)
        if o.trace is not None and v.explorer is not None:
            detail += "\n" + "\n".join(trace_lines(v.explorer, o.trace))
        out.append(
            f"::{kind} file={_gh(shown(file), True)},line={line},title={_gh('llfsm verify', True)}::{_gh(detail)}\n"
        )
    if v.error is not None:
        out.append(f"::error title=llfsm verify::{_gh('machine code raised while exploring: ' + v.error)}\n")
    return "".join(out)


def sarif(v: Verification, version: str) -> str:
    results: list[dict[str, Any]] = []
    for o in v.outcomes:
        if o.verdict == "holds":
            continue
        file, line = _location(o, v)
        detail = _line(o, v)
        if o.trace is not None and v.explorer is not None:
            detail += "\n" + "\n".join(trace_lines(v.explorer, o.trace))
        results.append(
            {
                "ruleId": "property-fails" if o.verdict == "fails" else "property-unknown",
                "level": "error" if o.verdict == "fails" else "warning",
                "message": {"text": detail},
                "locations": [
                    {
                        "physicalLocation": {
                            "artifactLocation": {"uri": file_uri(Path(file).as_posix())},
                            "region": {"startLine": line},
                        }
                    }
                ],
            }
        )
    rules = [
        {
            "id": "property-fails",
            "name": "property-fails",
            "shortDescription": {"text": "A property does not hold: the message holds a counterexample."},
            "defaultConfiguration": {"level": "error"},
        },
        {
            "id": "property-unknown",
            "name": "property-unknown",
            "shortDescription": {"text": "A property was not decided (state limit, interrupted)."},
            "defaultConfiguration": {"level": "warning"},
        },
    ]
    for r in results:
        r["ruleIndex"] = 0 if r["ruleId"] == "property-fails" else 1
    doc: dict[str, Any] = {
        "$schema": "https://json.schemastore.org/sarif-2.1.0.json",
        "version": "2.1.0",
        "runs": [
            {
                "tool": {
                    "driver": {
                        "name": "llfsm verify",
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


def render(v: Verification, fmt: str, version: str, witnesses: bool = False) -> str:
    if fmt == "json":
        return as_json(v)
    if fmt == "github":
        return github(v)
    if fmt == "sarif":
        return sarif(v, version)
    return text(v, witnesses)
