"""The seed's demos do what the documents describe (all under the sim clock)."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import yaml
from helpers import MACHINES, llfsm, llfsm_process, run_sim

PING = MACHINES / "ros2_ping_pong.machine"
BLIND = MACHINES / "ros2_blind_turtle_bot.machine"
WALL = MACHINES / "ros2_wall_turtle_bot.machine"
SUSPENDER = MACHINES / "ros2_turtle_suspend_resume.machine"
FOLLOWER = MACHINES / "turtle_follower.machine"
WORLD = 11.088889


def docs(stdout: str) -> list[dict]:
    return [d for d in yaml.safe_load_all(stdout) if d is not None]


def poses(*args: str | Path, topic: str = "/turtle1/pose") -> list[dict]:
    r = run_sim(*args, "--echo", topic)
    assert r.status == 0, r.stderr
    return docs(r.stdout)


def events(path: Path) -> list[dict]:
    return [json.loads(x) for x in path.read_text().splitlines()]


def test_all_demo_machines_check_clean_and_strict() -> None:
    r = llfsm("check", "--strict", MACHINES)
    assert r.status == 0, r.stdout
    shipped = len(list(MACHINES.glob("*.machine")))
    assert shipped >= 7 and f"checked {shipped} machine(s): 0 error(s), 0 warning(s)" in r.stderr


def test_ping_pong_counts_up_once_a_second() -> None:
    r = run_sim(PING, "--duration", "5.5s", "--echo", "/pingpong")
    assert r.status == 0
    assert [d["data"] for d in docs(r.stdout)] == [f"The count is {i}" for i in range(5)]
    stamps = [float(line.split("] [")[1]) for line in r.stderr.splitlines() if "Publishing:" in line]
    assert len(stamps) == 5
    gaps = [b - a for a, b in itertools.pairwise(stamps)]
    assert all(abs(g - 1.0) < 0.01 for g in gaps), gaps
    assert "[INFO] [1.002000000] [ros_ping_pong]: Publishing: 'The count is 0'" in r.stderr


def test_blind_turtle_walks_straight_and_turns_right_in_turn(tmp_path: Path) -> None:
    ps = poses(BLIND, "--node", "turtlesim", "--duration", "8.5s")
    moving = [p for p in ps if p["linear_velocity"] > 1.9]
    turning = [p for p in ps if p["angular_velocity"] < -1.9]
    assert len(moving) > 100 and len(turning) > 100  # about half of the time each
    assert not [p for p in ps if p["linear_velocity"] > 0.1 and abs(p["angular_velocity"]) > 0.1]
    first_straight = [p["x"] for p in ps[60:120]]
    assert first_straight == sorted(first_straight)  # heading 0: straight means x grows
    # each turn is right by about 2 rad (1 s at -2 rad/s): the corners of its "triangles"
    second_straight = next(p for p in ps[150:] if p["linear_velocity"] > 1.9)
    assert abs(second_straight["theta"] - (-2.0)) < 0.1, second_straight


def test_wall_turtle_backs_off_the_border_and_stays_inside(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    r = run_sim(
        WALL,
        "--node",
        "turtlesim",
        "--node",
        "turtle_sensor_poster",
        "--duration",
        "90s",
        "--echo",
        "/turtle1/pose",
        "--trace",
        trace,
    )
    assert r.status == 0
    ps = docs(r.stdout)
    assert "Oh no! I hit the wall!" not in r.stderr
    assert all(0.0 < p["x"] < WORLD and 0.0 < p["y"] < WORLD for p in ps)  # never clamped at a wall
    entered = [e["state"] for e in events(trace) if e["event"] == "entry"]
    assert entered.count("BACK") >= 3 and entered.count("TURN_RIGHT") >= 3
    assert "SERVICE_FAILS" not in entered
    # it went somewhere: the turtle explored more than a small patch
    xs, ys = [p["x"] for p in ps], [p["y"] for p in ps]
    assert max(xs) - min(xs) > 4 and max(ys) - min(ys) > 4


def test_wall_turtle_without_the_poster_reaches_service_fails_and_ends_by_itself(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    r = run_sim(WALL, "--node", "turtlesim", "--trace", trace)  # no --duration: it must end on its own
    assert r.status == 0
    entered = [e["state"] for e in events(trace) if e["event"] == "entry"]
    assert entered == ["INITIAL", "STRAIGHT", "STOP", "SERVICE_FAILS", "END"]
    assert "/turtle_pose_service did not answer (TIMEOUT)" in r.stderr


def test_suspend_resume_visibly_suspends_the_blind_bot(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    r = run_sim(
        SUSPENDER, BLIND, "--node", "turtlesim", "--duration", "12s", "--trace", trace, "-v", "--echo", "/turtle1/pose"
    )
    assert r.status == 0
    ev = [e for e in events(trace) if e["machine"] == "ros2_blind_turtle_bot"]
    assert sum(e["event"] == "suspend" for e in ev) >= 5
    assert sum(e["event"] == "resume" for e in ev) >= 5
    assert "m  1 s  4 - ros2_blind_turtle_bo - SUSPENDED" in r.stderr  # clfsm's %-20.20s
    # resuming re-enters the bot's state: its moves last longer than the plain bot's
    alone = poses(BLIND, "--node", "turtlesim", "--duration", "12s")
    together = docs(r.stdout)

    def reach(ps: list[dict]) -> float:
        return max(math.dist((p["x"], p["y"]), (ps[0]["x"], ps[0]["y"])) for p in ps)

    assert reach(together) > 1.4 * reach(alone)


def test_follower_closes_in_on_a_moving_leader(tmp_path: Path) -> None:
    leader = poses(BLIND, FOLLOWER, "--node", "turtlesim", "--duration", "30s")
    follower = poses(BLIND, FOLLOWER, "--node", "turtlesim", "--duration", "30s", topic="/turtle2/pose")
    assert len(leader) == len(follower) > 1000
    gaps = [math.dist((a["x"], a["y"]), (b["x"], b["y"])) for a, b in zip(leader, follower, strict=True)]
    travelled = sum(math.dist((a["x"], a["y"]), (b["x"], b["y"])) for a, b in itertools.pairwise(leader))
    assert travelled > 20  # the leader keeps moving
    late = gaps[len(gaps) // 2 :]
    assert sum(late) / len(late) < 1.5  # stays close while the leader keeps moving
    assert max(abs(b["angular_velocity"]) for b in follower) <= 4.0 + 1e-6  # bounded commands
    assert max(b["linear_velocity"] for b in follower) <= 2.0 + 1e-6


def test_follower_turns_the_short_way_and_rests_in_the_dead_zone(tmp_path: Path) -> None:
    # the leader stands still, just above-left of the follower's spawn point (6.0, 5.0, heading 0):
    # the short way round is left (positive angular velocity), and the follower then stops close by
    follower = poses(FOLLOWER, "--node", "turtlesim", "--duration", "10s", topic="/turtle2/pose")
    first_turn = next(p["angular_velocity"] for p in follower if abs(p["angular_velocity"]) > 0.01)
    assert first_turn > 0
    end = follower[-1]
    assert math.dist((end["x"], end["y"]), (5.544445, 5.544445)) < 0.7
    assert end["linear_velocity"] == 0 and end["angular_velocity"] == 0


def test_the_picture_of_a_run(tmp_path: Path) -> None:
    from PIL import Image

    png = tmp_path / "blind.png"
    svg = tmp_path / "blind.svg"
    assert run_sim(BLIND, "--node", "turtlesim", "--duration", "6s", "--image", png).status == 0
    assert run_sim(BLIND, "--node", "turtlesim", "--duration", "6s", "--image", svg).status == 0
    img = Image.open(png).convert("RGB")
    assert img.size == (500, 500)
    assert img.getpixel((5, 5)) == (69, 86, 255)  # turtlesim's background
    trail = (179, 184, 255)
    assert img.getcolors(maxcolors=1 << 16) is not None
    assert dict((c, n) for n, c in img.getcolors(maxcolors=1 << 16)).get(trail, 0) > 200  # the pen trail
    assert svg.read_text().lstrip().startswith("<")
    r = run_sim(BLIND, "--duration", "1s", "--image", png)
    assert r.status == 2 and "--node turtlesim" in r.stderr


def test_background_parameters_reach_the_picture(tmp_path: Path) -> None:
    from PIL import Image

    png = tmp_path / "bg.png"
    r = run_sim(
        BLIND,
        "--node",
        "turtlesim",
        "--param",
        "turtlesim:background_r:=0",
        "--param",
        "turtlesim:background_g:=0",
        "--param",
        "turtlesim:background_b:=0",
        "--duration",
        "1s",
        "--image",
        png,
    )
    assert r.status == 0
    assert Image.open(png).convert("RGB").getpixel((5, 5)) == (0, 0, 0)


def test_teleop_drives_turtle1_and_can_be_remapped_to_turtle2(tmp_path: Path) -> None:
    keys = tmp_path / "keys"
    keys.write_bytes(b"\x1b[A" * 5)  # five presses of the up arrow, one read every 100 ms

    def run(*extra: str) -> list[dict]:
        with open(keys, "rb") as stdin:
            r = llfsm_process(
                "run", "--clock", "sim", FOLLOWER, "--node", "turtlesim", "--node", "teleop",
                "--duration", "5s", "--echo", "/turtle1/pose", *extra, stdin=stdin,
            )  # fmt: skip
        assert r.status == 0, r.stderr
        assert "Use arrow keys to move the turtle." in r.stderr
        return docs(r.stdout)

    ps = run()
    # forward at 2.0 m/s from the first key (0.1 s) until 1 s after the last (0.5 s): about 2.8 m
    assert 5.544445 + 2.6 < max(p["x"] for p in ps) < 5.544445 + 3.0
    ps = run("--remap", "teleop_turtle:turtle1/cmd_vel:=turtle2/cmd_vel")
    assert max(p["x"] for p in ps) < 5.6  # turtle1 stays put: the keys drive turtle2
    keys.write_bytes(b"\x1b[Aq")
    trace = tmp_path / "t.jsonl"
    ps = run("--trace", str(trace))  # q ends the run like Ctrl-C: the follower takes its END transition
    finished = [json.loads(x) for x in trace.read_text().splitlines() if '"finish"' in x]
    assert finished and finished[0]["state"] == "END" and finished[0]["t"] < 1.5


def test_the_live_view_runs_headless(tmp_path: Path) -> None:
    import os

    env = dict(os.environ, SDL_VIDEODRIVER="dummy", SDL_AUDIODRIVER="dummy")
    r = llfsm_process("run", "--clock", "sim", BLIND, "--node", "turtlesim", "--view", "--duration", "2s", env=env)
    assert r.status == 0, r.stderr
    assert "Traceback" not in r.stderr
