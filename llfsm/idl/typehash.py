"""RIHS01 type hashes (REP 2011), computed from a type's description as
rosidl_generator_type_description computes them: what ROS 2 (Iron and later) puts in every
endpoint's USER_DATA as `typehash=...;` (docs/transports.md, "What a ROS 2 peer sees").

The generated `_dds` modules carry the hashes as constants (TYPE_HASHES), so running never
computes one; tests/interop compares them with the ones rosidl writes.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable

from .spec import ActionSpec, FieldSpec, FieldType, MessageSpec, ServiceSpec

Lookup = Callable[[str], MessageSpec]

# The stand-in member rosidl gives an empty message (IDL structs need one): a uint8 0 on the wire.
EMPTY_MEMBER = "structure_needs_at_least_one_member"

# type_description_interfaces/msg/FieldType ids (rosidl_generator_type_description).
_TYPE_IDS = {
    "int8": 2,
    "uint8": 3,
    "char": 3,  # .msg char is IDL uint8
    "int16": 4,
    "uint16": 5,
    "int32": 6,
    "uint32": 7,
    "int64": 8,
    "uint64": 9,
    "float32": 10,
    "float64": 11,
    "bool": 15,
    "byte": 16,
    "string": 17,
    "wstring": 18,
}
_ARRAY_OFFSET = {None: 0, "fixed": 48, "bounded": 96, "unbounded": 144}


def _wire_fields(spec: MessageSpec) -> list[FieldSpec]:
    """The members on the wire: an empty message has rosidl's stand-in uint8."""
    return spec.fields or [FieldSpec(EMPTY_MEMBER, FieldType("uint8"))]


def _field_description(f: FieldSpec) -> dict[str, object]:
    t = f.type
    base = 1 if t.is_message else _TYPE_IDS[t.base]
    if t.string_bound is not None:
        base = 21 if t.base == "string" else 22
    return {
        "name": f.name,
        "type": {
            "type_id": base + _ARRAY_OFFSET[t.array],
            "capacity": t.size or 0,
            "string_capacity": t.string_bound or 0,
            "nested_type_name": t.base if t.is_message else "",
        },
    }


def _individual(spec: MessageSpec) -> dict[str, object]:
    return {"type_name": spec.type_name, "fields": [_field_description(f) for f in _wire_fields(spec)]}


def _nested(f: FieldSpec) -> str | None:
    return f.type.base if f.type.is_message else None


def type_hash(top: MessageSpec, lookup: Lookup) -> str:
    """RIHS01_<sha256> of the type description of `top` and every type it references, as
    rosidl_generator_type_description computes it: compact JSON with ", " and ": " separators,
    referenced types sorted by name, default values left out."""
    seen: dict[str, MessageSpec] = {}
    queue = [n for f in _wire_fields(top) if (n := _nested(f))]
    while queue:
        name = queue.pop()
        if name in seen:
            continue
        spec = lookup(name)
        seen[name] = spec
        queue += [n for f in _wire_fields(spec) if (n := _nested(f))]
    description = {
        "type_description": _individual(top),
        "referenced_type_descriptions": [_individual(seen[n]) for n in sorted(seen)],
    }
    text = json.dumps(description, ensure_ascii=True, allow_nan=False, separators=(", ", ": "))
    return "RIHS01_" + hashlib.sha256(text.encode("utf-8")).hexdigest()


def service_specs(service: ServiceSpec) -> tuple[MessageSpec, MessageSpec]:
    """The two messages a service's type description adds beside Request and Response (ROS 2
    Iron and later): the service itself (request_message, response_message, event_message) and
    its Event (info, request[<=1], response[<=1])."""
    name = service.type_name
    event = MessageSpec(
        f"{name}_Event",
        [
            FieldSpec("info", FieldType("service_msgs/msg/ServiceEventInfo")),
            FieldSpec("request", FieldType(f"{name}_Request", array="bounded", size=1)),
            FieldSpec("response", FieldType(f"{name}_Response", array="bounded", size=1)),
        ],
    )
    whole = MessageSpec(
        name,
        [
            FieldSpec("request_message", FieldType(f"{name}_Request")),
            FieldSpec("response_message", FieldType(f"{name}_Response")),
            FieldSpec("event_message", FieldType(f"{name}_Event")),
        ],
    )
    return whole, event


def action_spec(action: ActionSpec) -> MessageSpec:
    """The message an action's type description describes (rosidl_generator_type_description's
    add_action): its three sections, its two services and its feedback message, as members."""
    name = action.type_name
    return MessageSpec(
        name,
        [
            FieldSpec("goal", FieldType(action.goal.type_name)),
            FieldSpec("result", FieldType(action.result.type_name)),
            FieldSpec("feedback", FieldType(action.feedback.type_name)),
            FieldSpec("send_goal_service", FieldType(f"{name}_SendGoal")),
            FieldSpec("get_result_service", FieldType(f"{name}_GetResult")),
            FieldSpec("feedback_message", FieldType(f"{name}_FeedbackMessage")),
        ],
    )
