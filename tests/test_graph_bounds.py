"""A peer whose ros_discovery_info names endpoints that never appear (SPEC §18, issue 28 item 8):
`node list`, `topic list` and `service list` wait for the endpoints a participant names (issue
22), but no longer than ENDPOINT_GRACE_S after it named them, once per verb: `node list` waited
twice SETTLE_S (11.4 s instead of 1.4 s).  The peer is a real DDS process in a private network
namespace; the wait is read on a clock the test moves, so no test waits for it in earnest."""

from __future__ import annotations

import json
import sys
import textwrap

import pytest
from dds_netns import RAW_PEER, NetNamespace, finish
from helpers import REPO

pytestmark = pytest.mark.dds

#: ros_discovery_info naming the node /ghost, whose reader and writer never exist.
GHOST = RAW_PEER + textwrap.dedent(
    """
    import os
    from llfsm.msgs import _dds
    from llfsm.msgs.rmw_dds_common.msg import Gid, NodeEntitiesInfo
    latched = (Policy.Durability.TransientLocal, Policy.History.KeepLast(1))
    info = writer("ros_discovery_info", ParticipantEntitiesInfo, *latched)
    node = NodeEntitiesInfo(node_namespace="/", node_name="ghost",
                            reader_gid_seq=[Gid(data=list(os.urandom(16)))],
                            writer_gid_seq=[Gid(data=list(os.urandom(16)))])
    message = ParticipantEntitiesInfo(gid=Gid(data=list(dp.get_guid().bytes)), node_entities_info_seq=[node])
    write(info, _dds.codec(ParticipantEntitiesInfo).cdr(message))
    print("named", flush=True)
    time.sleep(300)
    """
)

#: A graph reader that sees the ghost, then settles on a clock that moves only when it sleeps:
#: how long (on that clock) the settling waited.
SETTLE = textwrap.dedent(
    """
    import json, time, types
    from llfsm.ros.transports import dds_graph
    g = dds_graph.Graph()
    assert g.spin(30, until=lambda: any(n.full_name == "/ghost" for n in g.nodes()))
    virtual = [time.monotonic()]
    dds_graph.time = types.SimpleNamespace(monotonic=lambda: virtual[0],
                                           sleep=lambda s: virtual.__setitem__(0, virtual[0] + s))
    start = virtual[0]
    g.settle()
    print(json.dumps({"waited": virtual[0] - start, "settle_s": dds_graph.SETTLE_S,
                      "grace_s": getattr(dds_graph, "ENDPOINT_GRACE_S", None)}))
    """
)


def test_endpoints_that_never_appear_are_waited_for_once_and_briefly(netns: NetNamespace) -> None:
    peer = netns.python(GHOST)
    assert peer.stdout is not None and peer.stdout.readline().strip() == "named"
    status, out, err = finish(netns.python(SETTLE), 60)
    assert status == 0, err
    got = json.loads(out.strip().splitlines()[-1])
    assert got["waited"] <= 1.05 and got["settle_s"] == 5.0, got  # ENDPOINT_GRACE_S after the naming, a sleep's step
    nodes = finish(netns.popen([sys.executable, "-m", "llfsm", "node", "list", "--spin-time", "0.5"], cwd=REPO), 60)
    assert nodes[:2] == (0, "/ghost\n"), nodes
    for verb in ("topic", "service"):  # the ghost has no endpoints: nothing found, said as usual
        status, out, err = finish(netns.popen([sys.executable, "-m", "llfsm", verb, "list"], cwd=REPO), 60)
        assert (status, out) == (1, "") and f"no {verb}s found" in err, (verb, status, out, err)
    peer.kill()
