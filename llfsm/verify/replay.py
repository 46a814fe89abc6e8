"""`--counterexample DIR`: a counterexample's inputs as a rosbag2 bag that `llfsm run --clock sim
--period P --play DIR` replays to the same configuration (docs/verify.md, "Replaying a
counterexample").

Under `--period P` the explorer follows the run's timing exactly: round r of a path starts at
run time r*P, and an input bound to a topic takes, at each ringlet, the field of the newest
message there.  So for each round the bag holds one message per bound topic, at r*P, with the
values the path's ringlets of that round read: the player publishes it between rounds r-1 and
r, the input's reader hands it over, and the ringlets of round r take it as their snapshot.
Round 0 needs no message (the explorer gives bound inputs their defaults in the first round, as
a run does: no message can have come yet).  The bag is marked as holding run times (as a bag
llfsm records under `--clock sim`), so the player keeps them.

What a bag cannot carry is refused with the reason: an input bound to no topic that the path
gives another value than its default, two values of one field in one round, `ros.ok()`
falling (a signal, not a message).

Beside the bag, `steps.jsonl` holds the path itself in `--trace`'s format (llfsm.runtime.trace):
each machine's description and first values, then per step the states entered, the commands,
the transition, the variables that changed, and a `step` event with the inputs, the topics
published and the environment's choices; `llfsm replay DIR` steps through it on the diagrams
(docs/debug.md, "Replay").

The suggested `--duration` covers one round more than the path when its last step fired a
transition: `-v` prints a state's line before the ringlet that enters it, so only then does the
replayed trace show the state the counterexample ends in.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

from ..props.parse import duration_text
from ..runtime.inputs import DEFAULT, FIELD, MSG, NAME, TOPIC
from ..runtime.readout import description, plain
from .explorer import Explorer
from .judge import Trace, Verification
from .snapshot import STATE
from .values import shown as value_text

#: The file of the path's steps beside the bag.
STEPS = "steps.jsonl"


class ReplayError(Exception):
    """The counterexample cannot be written as a bag (the message says why)."""


def check_folder(folder: str) -> None:
    """Before exploring: ReplayError when no bag could be written in `folder` (the bag extra is
    missing, or the folder exists), so the user hears it before waiting for the verdict."""
    from ..bag import BagError, need_libraries  # deferred: start-up (bags are an optional extra)

    try:
        need_libraries()
    except BagError as e:
        raise ReplayError(str(e)) from None
    if os.path.lexists(folder):
        raise ReplayError(f"output folder '{folder}' already exists")


def _chosen(v: Verification) -> tuple[str, Trace]:
    for o in v.outcomes:
        if o.verdict == "fails" and o.trace is not None:
            return o.prop.name, o.trace
    if v.error_trace is not None and v.error_trace.steps:
        return "machine code raised", v.error_trace
    raise ReplayError("no property failed with a counterexample: no bag written")


def messages(v: Verification, trace: Trace) -> tuple[list[tuple[int, str, Any]], int]:
    """(run time, topic, message) of each message the path needs, in order, and its rounds."""
    e = v.explorer
    assert e is not None and e.period is not None
    from ..ros.inputs import message_class  # deferred: start-up (only a counterexample bag needs messages)

    period = e.period
    wanted: dict[int, dict[str, dict[str, Any]]] = {}  # round -> topic -> field -> value
    types: dict[str, str] = {}
    rounds = 0
    for _config, step in trace.steps[1:]:
        if step is None:
            continue
        rounds = max(rounds, step.round + 1)
        if step.interrupted:
            raise ReplayError(f"in round {step.round} ros.ok() falls (--interrupt): a bag cannot carry a signal")
        m = e.machines[step.machine]
        for entry in m.INPUTS:
            value = step.inputs[entry[NAME]]
            if entry[TOPIC] is None:
                if value != entry[DEFAULT]:
                    raise ReplayError(
                        f"input {entry[NAME]} of {m.NAME} is bound to no topic, so a run keeps its default "
                        f"{entry[DEFAULT]!r}, but the counterexample needs {value!r} in round {step.round}"
                    )
                continue
            if step.round == 0:
                continue  # the default, as in a run (the explorer chose nothing else)
            topic = entry[TOPIC] if entry[TOPIC].startswith("/") else "/" + entry[TOPIC]
            types.setdefault(topic, entry[MSG])
            fields = wanted.setdefault(step.round, {}).setdefault(topic, {})
            field = entry[FIELD]
            if field in fields and fields[field] != value:
                raise ReplayError(
                    f"round {step.round} needs {topic} {field} to be both {fields[field]!r} and {value!r}: "
                    "one message per round cannot give both"
                )
            fields[field] = value
    out = []
    current: dict[str, Any] = {}
    for r in sorted(wanted):
        for topic, fields in sorted(wanted[r].items()):
            msg = current.get(topic)
            msg = message_class(types[topic])() if msg is None else msg._copy()
            for path, value in fields.items():
                target = msg
                *parents, last = path.split(".")
                for name in parents:
                    target = getattr(target, name)
                kind = type(getattr(target, last))
                setattr(target, last, kind(value))
            current[topic] = msg
            out.append((r * period, topic, msg))
    return out, rounds


def write_counterexample(v: Verification, folder: str) -> str:
    """Write the bag of the first counterexample; what to tell the user."""
    from ..bag import BagError  # deferred: start-up (bags are an optional extra)
    from ..bag.recorder import SIM_CLOCK_KEY
    from ..bag.typesupport import TypeSupport
    from ..bag.writer import BagWriter, qos_profile

    e = v.explorer
    if e is None or e.period is None:
        raise ReplayError("needs --period: only then does the explorer follow a run's timing exactly")
    name, trace = _chosen(v)
    msgs, rounds = messages(v, trace)
    created = not os.path.lexists(folder)
    try:
        writer = BagWriter(folder)
        writer.custom[SIM_CLOCK_KEY] = "sim"
        types = TypeSupport()
        for t, topic, msg in msgs:
            cls = type(msg)
            definition, type_hash = types.definition(cls._TYPE)
            conn = writer.connection(topic, cls._TYPE, definition, type_hash, [qos_profile()])
            writer.write(conn, t, types.serializer(cls)(msg))
        writer.close()
    except (BagError, ImportError) as e2:  # ImportError: a broken bag extra (check_folder saw it installed)
        if created:
            shutil.rmtree(folder, ignore_errors=True)  # never a half-written bag
        why = f"{e2.name} cannot be imported: pip install 'llfsm[bag]'" if isinstance(e2, ImportError) else str(e2)
        raise ReplayError(why) from None
    try:
        (Path(folder) / STEPS).write_text("".join(json.dumps(ev) + "\n" for ev in steps_events(e, trace)))
    except OSError as e3:
        raise ReplayError(f"{folder}: {STEPS} could not be written: {e3.strerror}") from None
    period = e.period
    last = next((step for _config, step in reversed(trace.steps) if step is not None), None)
    shown = rounds + 1 if last is not None and last.transition is not None else rounds
    targets = " ".join(str(Path(p)) for p in v.loaded.paths)
    return (
        f"wrote the counterexample of {name!r} to {folder} ({len(msgs)} message{'s' if len(msgs) != 1 else ''}, "
        f"{rounds} round{'s' if rounds != 1 else ''}); replay it with: llfsm run --clock sim --period "
        f"{duration_text(period)} --play {folder} --duration {duration_text(shown * period)} {targets}"
    )


def _value(x: Any) -> Any:
    """A configuration's value as plain data (a message or a frozen value as verify shows it)."""
    return x if isinstance(x, bool | int | float | str) or x is None else value_text(x)


def steps_events(e: Explorer, trace: Trace) -> list[dict[str, Any]]:
    """The path as `--trace` events (see the module's docstring), under --period's timing."""
    period = e.period or 0
    names = [m.NAME for m in e.machines]
    config0 = trace.steps[0][0]
    out: list[dict[str, Any]] = []
    for k, m in enumerate(e.machines):
        first = e.codecs[k].variables_of(e.part(config0, k))
        values = {n: plain(_value(v)) for n, v in first.items()}
        out.append(_event(0, 0, "machine", names, k, description=description(type(m)), variables=values))
    loop_start = None if trace.loop is None else trace.loop + 1
    for n, (config, step) in enumerate(trace.steps[1:], start=1):
        if n == loop_start:
            out.append({"event": "loop"})
        if step is None:
            out.append({"event": "ended"})
            continue
        i, t, r = step.machine, step.round * period, step.round
        states = e.machines[i].STATES
        for command, k, state in step.commands:
            out.append(_event(t, r, command, names, k, state=e.machines[k].STATES[state]))
        for k, state in step.entered:
            out.append(_event(t, r, "entry", names, k, state=e.machines[k].STATES[state]))
        after = states[e.part(config, i)[STATE]]
        if step.transition is not None:
            fired = {"source": states[step.state], "target": after, "index": step.transition}
            out.append(_event(t, r, "transition", names, i, **fired))
        by_machine: dict[str, dict[str, list[Any]]] = {}
        for name, (old, new) in step.changed.items():
            machine, _, var = name.partition(".")
            by_machine.setdefault(machine, {})[var] = [plain(_value(old)), plain(_value(new))]
        for machine, changed in by_machine.items():
            out.append(_event(t, r, "variables", names, names.index(machine), changed=changed))
        inputs = {k: plain(_value(v)) for k, v in step.inputs.items()}
        seen = {"inputs": inputs, "published": sorted(step.published), "time": step.interval}
        out.append(_event(t, r, "step", names, i, state=after, environment=step.environment, **seen))
        if step.finished:
            out.append(_event(t, r, "finish", names, i, state=after))
    return out


def _event(t: int, round_: int, kind: str, names: list[str], k: int, **fields: Any) -> dict[str, Any]:
    return {"t": t / 1e9, "round": round_, "event": kind, "machine": names[k], "id": k, **fields}
