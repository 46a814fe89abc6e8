"""Discovery settings for llfsm's DDS participant, from ROS 2's environment variables.

rmw_cyclonedds_cpp turns `ROS_DOMAIN_ID`, `ROS_AUTOMATIC_DISCOVERY_RANGE`, `ROS_STATIC_PEERS`
and `ROS_LOCALHOST_ONLY` into a Cyclone XML fragment placed *before* the user's own
`CYCLONEDDS_URI`, so that the user's settings win where both speak.  This module builds the
same fragment, so an llfsm run and an rmw_cyclonedds node with the same environment find each
other with the same settings:

| range | multicast | peers | participant index |
|---|---|---|---|
| SUBNET (default) | Cyclone's default | ROS_STATIC_PEERS | Cyclone's: none (multicast, no peers), else auto, max 119 |
| LOCALHOST | off | `localhost` + ROS_STATIC_PEERS | auto (max 119) |
| OFF | off | none | none, with a per-process domain tag |
| SYSTEM_DEFAULT | Cyclone's default | none (Cyclone's own config only) | Cyclone's default |

The participant index is where llfsm parts from rmw_cyclonedds_cpp 1.6+ (Iron on), which asks
for `auto` with at most 32 on every range but OFF, so that a host holds at most 33 ROS processes
(Humble's rmw left Cyclone's defaults: no limit with multicast).  An index only matters to
unicast discovery (it fixes the ports a peer tries), so llfsm leaves SUBNET's to Cyclone, which
takes `none` (no limit: the kernel picks the ports) when every interface multicasts and no peer
is named, and allows 120 (Cyclone's own bound, indices 0-119) wherever unicast discovery needs
one.  A participant that finds every index taken fails with one line saying so
(`participant`).

`ROS_LOCALHOST_ONLY=1` (deprecated in ROS 2, still honoured by rcl) means LOCALHOST and
ignores the other two variables.

One addition of llfsm's own, also placed before `CYCLONEDDS_URI` so a user can override it:
`Compatibility/IgnoreTypeInformation` for vendor 1.15 (eProsima Fast DDS), whose XTypes type
information Cyclone would otherwise use to refuse matches with rclpy's default middleware.

Use `participant()` for the run's one participant; `settings()` and `config_xml()` say what it
was made from (the CLI's graph reader shares them).
"""

from __future__ import annotations

import os
import sys
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

if TYPE_CHECKING:
    from cyclonedds.domain import DomainParticipant

RANGES = ("SUBNET", "LOCALHOST", "OFF", "SYSTEM_DEFAULT")
#: The highest participant index Cyclone gives a participant where discovery is unicast (its
#: own bound: ports are computed from it): 120 processes of one host on one domain.
MAX_AUTO_PARTICIPANT_INDEX = 119
#: Vendor ids whose discovery type information Cyclone ignores (1.15: eProsima Fast DDS).
IGNORE_TYPE_INFORMATION = "1.15"
#: Participant USER_DATA, as rmw sets it (the security enclave; llfsm runs in the root one).
ENCLAVE_USER_DATA = b"enclave=/;"


class DiscoveryError(ValueError):
    """An environment variable that cannot be read: a usage error naming the variable."""


@dataclass(frozen=True)
class Discovery:
    domain_id: int = 0
    range: str = "SUBNET"
    static_peers: tuple[str, ...] = ()
    #: Warnings rcl would log (static peers ignored, deprecated variable), for the caller to show.
    notes: tuple[str, ...] = field(default=(), compare=False)


def settings(env: Mapping[str, str] | None = None) -> Discovery:
    """The discovery settings the ROS 2 environment variables ask for (rcl's reading of them)."""
    env = os.environ if env is None else env
    raw_id = env.get("ROS_DOMAIN_ID", "").strip()
    if raw_id:
        try:
            domain_id = int(raw_id)
        except ValueError:
            raise DiscoveryError(f"ROS_DOMAIN_ID={raw_id!r}: expected an integer domain id (0-232)") from None
        if not 0 <= domain_id <= 232:
            raise DiscoveryError(f"ROS_DOMAIN_ID={raw_id}: a domain id is 0-232 (ports beyond are invalid)")
    else:
        domain_id = 0
    notes: list[str] = []
    raw_range = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip()
    if raw_range and raw_range.upper() not in RANGES:
        raise DiscoveryError(f"ROS_AUTOMATIC_DISCOVERY_RANGE={raw_range!r}: expected one of {', '.join(RANGES)}")
    rng = raw_range.upper() or "SUBNET"
    peers = tuple(p.strip() for p in env.get("ROS_STATIC_PEERS", "").split(";") if p.strip())
    if env.get("ROS_LOCALHOST_ONLY", "").strip() == "1":
        if raw_range or peers:
            notes.append(
                "ROS_LOCALHOST_ONLY is deprecated but still honoured: ROS_AUTOMATIC_DISCOVERY_RANGE and "
                "ROS_STATIC_PEERS are ignored"
            )
        rng, peers = "LOCALHOST", ()
    if rng in ("OFF", "SYSTEM_DEFAULT") and peers:
        why = "discovery is turned off" if rng == "OFF" else "discovery is left to Cyclone's own configuration"
        notes.append(f"{len(peers)} static peers were specified, but {why}, so they are ignored")
        peers = ()
    return Discovery(domain_id, rng, peers, tuple(notes))


def ros_fragment(d: Discovery, pid: int | None = None) -> str:
    """The XML rmw_cyclonedds_cpp puts before CYCLONEDDS_URI for these settings ('' if none)."""
    if d.range == "SYSTEM_DEFAULT":
        return ""
    localhost = d.range == "LOCALHOST"
    no_multicast = d.range in ("LOCALHOST", "OFF")
    out = ["<CycloneDDS><Domain>"]
    if no_multicast:
        out.append("<General><AllowMulticast>false</AllowMulticast></General>")
    if d.range == "OFF":
        # only a participant with this exact tag (down to the process id) could discover us
        out.append("<Discovery><ParticipantIndex>none</ParticipantIndex>")
        out.append(f"<Tag>ros_discovery_off_{os.getpid() if pid is None else pid}</Tag>")
    elif localhost:
        out.append("<Discovery><ParticipantIndex>auto</ParticipantIndex>")
        out.append(f"<MaxAutoParticipantIndex>{MAX_AUTO_PARTICIPANT_INDEX}</MaxAutoParticipantIndex>")
    else:  # SUBNET: Cyclone picks none (multicast, no peers) or auto (module docstring)
        out.append(f"<Discovery><MaxAutoParticipantIndex>{MAX_AUTO_PARTICIPANT_INDEX}</MaxAutoParticipantIndex>")
    peers = (["localhost"] if localhost else []) + list(d.static_peers)
    if peers:
        out.append("<Peers>" + "".join(f"<Peer address={quoteattr(p)}/>" for p in peers) + "</Peers>")
    out.append("</Discovery></Domain></CycloneDDS>")
    return "".join(out)


def llfsm_fragment() -> str:
    """llfsm's own defaults (Fast DDS interop), which a user's CYCLONEDDS_URI may override."""
    return (
        "<CycloneDDS><Domain><Compatibility>"
        f"<IgnoreTypeInformation>{IGNORE_TYPE_INFORMATION}</IgnoreTypeInformation>"
        "</Compatibility></Domain></CycloneDDS>"
    )


def config_xml(env: Mapping[str, str] | None = None, d: Discovery | None = None) -> str:
    """The whole configuration handed to Cyclone: ours, then the user's CYCLONEDDS_URI (merged by
    Cyclone itself, later fragments winning), exactly as rmw_cyclonedds_cpp emulates it."""
    env = os.environ if env is None else env
    d = settings(env) if d is None else d
    parts = [p for p in (ros_fragment(d), llfsm_fragment()) if p]
    user = env.get("CYCLONEDDS_URI", "").strip()
    if user:
        parts.append(user)
    return ",".join(parts)


_domains: dict[int, object] = {}


def participant(domain_id: int | None = None, env: Mapping[str, str] | None = None) -> DomainParticipant:
    """A DomainParticipant on the ROS domain (ROS_DOMAIN_ID unless given), configured as
    rmw_cyclonedds_cpp configures its one, with participant USER_DATA `enclave=/;`.

    The domain's configuration is fixed by the first call in a process (Cyclone creates a domain
    once); later participants on the same domain share it.  Raises DiscoveryError for a bad
    variable and ImportError when the `cyclonedds` package is missing.
    """
    # deferred: optional dependency (the settings and the XML above need no cyclonedds)
    from cyclonedds.core import DDSException, Policy, Qos
    from cyclonedds.domain import Domain, DomainParticipant

    d = settings(env)
    did = d.domain_id if domain_id is None else domain_id
    if did not in _domains:
        with _cyclone_log() as said:
            try:
                _domains[did] = Domain(did, config_xml(env, d))
                failed = None
            except DDSException as e:
                failed = e
        if failed is not None:
            if "free participant index" in said.text:
                raise DiscoveryError(
                    f"no free participant index on this host for ROS domain {did}: Cyclone DDS numbers the "
                    "processes of a host where discovery is unicast (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or "
                    "ROS_STATIC_PEERS) up to Discovery/MaxAutoParticipantIndex (llfsm's default "
                    f"{MAX_AUTO_PARTICIPANT_INDEX}, Cyclone's most; CYCLONEDDS_URI may set it lower); with "
                    "multicast discovery (range SUBNET, no static peers) there is no limit, or give every "
                    "process <Discovery><ParticipantIndex>none</ParticipantIndex></Discovery> in CYCLONEDDS_URI"
                ) from None
            raise DiscoveryError(
                f"Cyclone DDS refused its configuration (check CYCLONEDDS_URI and the ROS_* variables): {failed}"
            ) from None
        sys.stderr.write(said.text)
    return DomainParticipant(did, qos=Qos(Policy.Userdata(ENCLAVE_USER_DATA)))


class _Said:
    text = ""


@contextmanager
def _cyclone_log() -> Iterator[_Said]:
    """What Cyclone writes on stderr (file descriptor 2) meanwhile, in `.text` afterwards: the
    reason a domain could not be made is only said there.  The caller shows it, or says it
    better.  Where fd 2 cannot be borrowed, nothing is caught and Cyclone speaks for itself."""
    said = _Said()
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield said
        return
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            caught.seek(0)
            said.text = caught.read().decode("utf-8", "replace")
