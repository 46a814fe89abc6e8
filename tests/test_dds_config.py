"""Discovery settings from ROS 2's environment variables, as rmw_cyclonedds_cpp builds them, and
the participant Cyclone accepts with them (a real Cyclone domain; no network traffic needed)."""

from __future__ import annotations

import pytest

from llfsm.ros.transports import dds_config as c


def test_defaults_are_domain_0_on_the_subnet() -> None:
    d = c.settings({})
    assert (d.domain_id, d.range, d.static_peers) == (0, "SUBNET", ())
    xml = c.config_xml({})
    # Cyclone chooses: none (no limit per host) with multicast and no peers, else auto (max 119)
    assert "ParticipantIndex>" not in xml.replace("MaxAutoParticipantIndex>", "")
    assert "<MaxAutoParticipantIndex>119</MaxAutoParticipantIndex>" in xml
    assert "AllowMulticast" not in xml
    assert "<IgnoreTypeInformation>1.15</IgnoreTypeInformation>" in xml


def test_localhost_turns_multicast_off_and_peers_with_localhost() -> None:
    env = {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_STATIC_PEERS": "192.168.1.7; ;robot.local"}
    frag = c.ros_fragment(c.settings(env))
    assert "<AllowMulticast>false</AllowMulticast>" in frag
    assert (
        '<Peers><Peer address="localhost"/><Peer address="192.168.1.7"/><Peer address="robot.local"/></Peers>' in frag
    )
    assert "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>119</MaxAutoParticipantIndex>" in frag


def test_off_uses_a_private_tag_and_ignores_peers() -> None:
    d = c.settings({"ROS_AUTOMATIC_DISCOVERY_RANGE": "off", "ROS_STATIC_PEERS": "10.0.0.1"})
    assert d.static_peers == () and d.notes
    frag = c.ros_fragment(d, pid=42)
    assert "<ParticipantIndex>none</ParticipantIndex><Tag>ros_discovery_off_42</Tag>" in frag
    assert "Peer" not in frag


def test_localhost_only_wins_over_the_range() -> None:
    d = c.settings({"ROS_LOCALHOST_ONLY": "1", "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET", "ROS_STATIC_PEERS": "a"})
    assert (d.range, d.static_peers) == ("LOCALHOST", ())
    assert "deprecated" in d.notes[0]


def test_system_default_leaves_cyclone_alone() -> None:
    assert c.ros_fragment(c.settings({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SYSTEM_DEFAULT"})) == ""


def test_the_users_cyclonedds_uri_comes_last_so_it_wins() -> None:
    xml = c.config_xml({"CYCLONEDDS_URI": "file:///etc/my.xml", "ROS_DOMAIN_ID": "7"})
    assert xml.endswith(",file:///etc/my.xml")
    assert c.settings({"ROS_DOMAIN_ID": "7"}).domain_id == 7


@pytest.mark.parametrize(
    "env",
    [{"ROS_DOMAIN_ID": "seven"}, {"ROS_DOMAIN_ID": "300"}, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "PLANET"}],
)
def test_bad_variables_are_named(env: dict[str, str]) -> None:
    with pytest.raises(c.DiscoveryError, match=next(iter(env))):
        c.settings(env)


@pytest.mark.dds
def test_cyclone_accepts_the_configuration_and_the_participant_carries_the_enclave() -> None:
    pytest.importorskip("cyclonedds")
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant
    from cyclonedds.core import Policy

    env = {"ROS_DOMAIN_ID": "97", "ROS_AUTOMATIC_DISCOVERY_RANGE": "OFF"}
    p = c.participant(env=env)
    assert p.get_domain_id() == 97
    reader = BuiltinDataReader(p, BuiltinTopicDcpsParticipant)
    mine = [s for s in reader.take(N=10) if s.key == p.get_guid()]
    assert mine and mine[0].qos[Policy.Userdata].data == b"enclave=/;"
