"""Services between Cyclone DDS (what llfsm speaks, through the `cyclonedds` package and the
generated types) and Fast DDS (rclpy's default rmw, from the wheels): what works and what cannot,
as docs/transports.md ("Services across DDS implementations") says."""

from __future__ import annotations

import json

import pytest

from interop.ros2env import python_command, requires_ros, ros_command, run_together

pytestmark = [pytest.mark.interop, pytest.mark.dds, requires_ros]

_QOS = r"""
from cyclonedds.qos import Qos, Policy
from cyclonedds.util import duration
QOS = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(100),
          Policy.Durability.Volatile, Policy.DataRepresentation(use_cdrv0_representation=True))
"""

_RCLPY_SERVER = r"""
import time, rclpy
from rclpy.node import Node
from std_srvs.srv import SetBool
rclpy.init()
node = Node("fast_server")
def answer(request, response):
    response.success = not request.data
    response.message = f"fast dds saw {request.data}"
    return response
node.create_service(SetBool, "toggle", answer)
deadline = time.monotonic() + 25
while time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.1)
"""

# A client as llfsm's transport makes one for a Fast DDS server: it learns the server's vendor
# from the GUID of the matched request reader, sends the bare request and takes the reply.
_CYCLONE_CLIENT = (
    _QOS
    + r"""
import json, time
from cyclonedds.domain import DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from llfsm.msgs import _dds
from llfsm.msgs.std_srvs.srv import SetBool
dp = DomainParticipant(0)
writer = DataWriter(dp, Topic(dp, "rq/toggleRequest", _dds.dds_type(SetBool.Request), qos=QOS), qos=QOS)
reader = DataReader(dp, Topic(dp, "rr/toggleReply", _dds.dds_type(SetBool.Response), qos=QOS), qos=QOS)
deadline = time.monotonic() + 15
while time.monotonic() < deadline and not (writer.get_matched_subscriptions() and reader.get_matched_publications()):
    time.sleep(0.05)
time.sleep(0.5)  # our side has matched; give the server's side time to match us too
server = writer.get_matched_subscription_data(writer.get_matched_subscriptions()[0])
header = _dds.carries_request_header(server.key)
answers = []
for value in (True, False):
    writer.write(_dds.to_dds(SetBool.Request(data=value)))
    while time.monotonic() < deadline:
        got = [s for s in reader.take(10) if s.sample_info.valid_data]
        if got:
            answers += [_dds.from_dds(s, SetBool.Response).to_dict() for s in got]
            break
        time.sleep(0.02)
print(json.dumps({"vendor": _dds.vendor_name(server.key), "header": header, "answers": answers}))
"""
)


def test_llfsm_style_client_gets_answers_from_fast_dds_server() -> None:
    _server, client = run_together(
        [ros_command(_RCLPY_SERVER), python_command(_CYCLONE_CLIENT)], timeout=40, stop_after_first=1
    )
    assert client.returncode == 0, client.stderr
    out = json.loads(client.stdout.strip().splitlines()[-1])
    assert out == {
        "vendor": "eProsima Fast DDS",
        "header": False,
        "answers": [
            {"success": False, "message": "fast dds saw True"},
            {"success": True, "message": "fast dds saw False"},
        ],
    }


_RCLPY_CLIENT = r"""
import json, rclpy
from rclpy.node import Node
from std_srvs.srv import SetBool
rclpy.init()
node = Node("fast_client")
client = node.create_client(SetBool, "toggle")
ready = client.wait_for_service(timeout_sec=15)
answered = []
for _ in range(3):  # the first request may go out before the server's reader has matched it
    future = client.call_async(SetBool.Request(data=True))
    rclpy.spin_until_future_complete(node, future, timeout_sec=1.5)
    answered.append(future.done())
print(json.dumps({"ready": ready, "answered": any(answered)}))
"""

# A server on Cyclone: reads the bare request of a Fast DDS client (its writer's GUID says so),
# and answers, but cannot attach the related sample identity Fast DDS clients wait for.
_CYCLONE_SERVER = (
    _QOS
    + r"""
import json, time
from cyclonedds.domain import DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from llfsm.msgs import _dds
from llfsm.msgs.std_srvs.srv import SetBool
dp = DomainParticipant(0)
reader = DataReader(dp, Topic(dp, "rq/toggleRequest", _dds.dds_type(SetBool.Request), qos=QOS), qos=QOS)
writer = DataWriter(dp, Topic(dp, "rr/toggleReply", _dds.dds_type(SetBool.Response), qos=QOS), qos=QOS)
deadline = time.monotonic() + 25
while time.monotonic() < deadline:
    for s in reader.take(10):
        if s.sample_info.valid_data:
            client = reader.get_matched_publication_data(s.sample_info.publication_handle)
            print(json.dumps([_dds.from_dds(s, SetBool.Request).data, _dds.vendor_name(client.key)]), flush=True)
            writer.write(_dds.to_dds(SetBool.Response(success=True, message="from cyclone")))
    time.sleep(0.02)
"""
)


def test_fast_dds_client_gets_no_answer_from_cyclone_server() -> None:
    """The request arrives and is served, but rmw_fastrtps_cpp drops the reply: it keeps only
    replies whose RTPS related-sample-identity names its own request, which Cyclone DDS does not
    send.  When this starts to pass the other way, docs/transports.md needs updating."""
    client, server = run_together(
        [ros_command(_RCLPY_CLIENT), python_command(_CYCLONE_SERVER)], timeout=40, stop_after_first=0
    )
    assert server.returncode == -15, server.stderr  # ended by run_together once the client is done
    assert client.returncode == 0, client.stderr
    seen = [json.loads(line) for line in server.stdout.splitlines()]
    assert seen and all(s == [True, "eProsima Fast DDS"] for s in seen), server.stdout
    assert json.loads(client.stdout.strip().splitlines()[-1]) == {"ready": True, "answered": False}
