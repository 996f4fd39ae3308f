"""Bad arguments raise BkpbsError (a ValueError) naming the culprit; a busy simulation slot
raises SimulationBusyError (a RuntimeError), never a crash."""

from __future__ import annotations

import threading
import time

import pytest

import bkpbs
from conftest import vehicle


def test_exception_hierarchy():
    assert issubclass(bkpbs.BkpbsError, ValueError)
    assert issubclass(bkpbs.SumoError, RuntimeError)
    assert issubclass(bkpbs.SimulationBusyError, bkpbs.SumoError)


def test_unknown_planner():
    with pytest.raises(bkpbs.BkpbsError, match=r"unknown planner 'bk-pbz' \(known: sumo, idm-mobil"):
        bkpbs.Controller("bk-pbz")
    with pytest.raises(ValueError, match="unknown planner 'nope'"):
        bkpbs.run_episode("nope", 0.5, 3000, 0, steps=5)


@pytest.mark.parametrize("alpha", [-0.1, 1.5])
def test_alpha_outside_unit_interval(alpha):
    with pytest.raises(ValueError, match=r"scenario.alpha = .*must lie in \[0, 1\]"):
        bkpbs.run_episode("idm-mobil", alpha, 3000, 0, steps=5)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"stepz": 5}, r"\[scenario\]: unknown field `stepz`"),
        ({"idm": {"acel": 2.0}}, r"\[idm\]: unknown field `acel`"),
        ({"idm": 2.0}, r"config section 'idm' must be given as a dict"),
        ({"config": {"nonsense": {}}}, r"unknown field `nonsense`"),
        ({"config": "[scenario]\nalhpa = 0.3\n"}, r"unknown field `alhpa`"),
        ({"config": "[scenario\n"}, r"malformed TOML configuration"),
        ({"config": "no/such/file.toml"}, r"cannot read config file no/such/file.toml"),
        ({"steps": "many"}, r"invalid type: string \"many\""),
        ({"steps": 0}, r"scenario.steps = 0: must be 1 to 100000 steps"),
        ({"dt": object()}, r"config key 'scenario.dt': unsupported value"),
    ],
)
def test_bad_configuration(kwargs, message):
    with pytest.raises(bkpbs.BkpbsError, match=message):
        bkpbs.run_episode("idm-mobil", 0.5, 3000, 0, **kwargs)


def test_config_file_is_read(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[scenario]\nsteps = 7\n[idm]\naccel = 2.5\n")
    text = bkpbs.config_toml(f)
    assert "steps = 7" in text and "accel = 2.5" in text
    assert "steps = 9" in bkpbs.config_toml(str(f), steps=9)
    f.write_text("[scenario]\nsteps = \n")
    with pytest.raises(ValueError, match=f"malformed config file {f}"):
        bkpbs.config_toml(f)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"speed": None}, r"vehicle 0 \('main.0'\): missing key 'speed'"),
        ({"speed": "fast"}, r"'speed' must be a finite number, got 'fast'"),
        ({"speed": float("nan")}, r"'speed' must be a finite number"),
        ({"lane_index": 1.5}, r"'lane_index' must be an integer"),
        ({"road_id": 3}, r"'road_id' must be a string"),
        ({"lane_pos": 3.0}, r"unknown key 'lane_pos' \(known: id, type"),
        ({"origin": "sky"}, r"'origin' must be \"main\" or \"ramp\""),
    ],
)
def test_malformed_vehicle(change, message):
    v = vehicle("main.0", "cav", "main_in", 0, 10.0, 30.0)
    for k, x in change.items():
        if x is None:
            del v[k]
        else:
            v[k] = x
    with pytest.raises(bkpbs.BkpbsError, match=message):
        bkpbs.Controller("idm-mobil").plan([v])


def test_vehicles_must_be_a_list_of_vehicles():
    c = bkpbs.Controller("idm-mobil")
    with pytest.raises(ValueError, match="vehicles must be a list"):
        c.plan(3)
    with pytest.raises(ValueError, match="vehicle 0: expected a dict"):
        c.plan([3])
    with pytest.raises(ValueError, match="vehicle 0: missing key 'id'"):
        c.plan([{"type": "cav"}])


def test_bad_model_files(tmp_path):
    with pytest.raises(bkpbs.BkpbsError, match="cannot read model file"):
        bkpbs.load_predictor(tmp_path / "model.json")
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(ValueError, match="bad.json"):
        bkpbs.Controller("bk-mastar", model=tmp_path / "bad.json")


def test_second_episode_in_one_process_is_refused_not_crashed():
    done = threading.Event()
    result = {}

    def long_episode():
        while True:  # a probe below may hold the slot for a moment: retry until it is ours
            try:
                result["summary"] = bkpbs.run_episode("sumo", 0.5, 3000, 0, steps=4000)
                break
            except bkpbs.SimulationBusyError:
                time.sleep(0.001)
        done.set()

    t = threading.Thread(target=long_episode)
    t.start()
    busy = None
    while not done.is_set():
        try:
            bkpbs.run_episode("sumo", 0.5, 3000, 1, steps=1)
        except bkpbs.SimulationBusyError as e:
            busy = e
            break
        time.sleep(0.005)
    t.join(timeout=120)
    assert busy is not None, "the second episode never overlapped the first"
    assert "already running in this process" in str(busy)
    assert result["summary"]["steps"] == 4000
