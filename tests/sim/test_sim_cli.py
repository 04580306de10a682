"""psorr-sim perceive: the cell's rendered cloud through the recognizer, graded against the simulator."""

import importlib
import json
import subprocess
import sys


def test_perceive_grades_detections_against_the_simulator(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sim.cli", "perceive", "--seed", "0", "--json",
                          "--out", str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout.strip().splitlines()[-1])
    assert record["parts"] == ["u_channel", "chassis", "transformer", "flanged_hub"]
    correct = [d for d in record["detections"] if d["correct"]]
    # Seed 0 is solved for u_channel and chassis today; any correct pose is millimetre-accurate.
    assert {d["model"] for d in correct} >= {"u_channel", "chassis"}
    assert all(d["add_mm"] < 5.0 and d["pos_mm"] < 5.0 and d["rot_deg"] < 3.0 for d in correct)
    assert (tmp_path / "rgb.png").exists() and (tmp_path / "recognition.png").exists()


def test_unknown_part_is_a_clear_error():
    out = subprocess.run([sys.executable, "-m", "sim.cli", "perceive", "--parts", "gearbox"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "gearbox" in out.stderr and "Traceback" not in out.stderr


def test_run_prints_the_summary_contract(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sim.cli", "run", "tasks/demo.yaml", "--episodes", "1",
                          "--poses", "oracle", "--json"], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    record = json.loads(out.stdout.strip().splitlines()[-1])
    assert set(record) == {"episodes", "picks", "grasp_success_rate", "place_success_rate",
                           "pose_error_mm_median", "rot_error_deg_median", "wall_s_per_episode"}
    assert record["episodes"] == 1 and record["picks"] == 4
    assert record["grasp_success_rate"] == 1.0 and record["place_success_rate"] == 1.0


def _in_process(capsys, module: str, *args: str) -> tuple[int, str]:
    """The exit status and stderr of ``python -m module args``, run in this process: a usage error needs none
    of its own (an unexpected exception fails the test as a traceback would)."""
    try:
        status = importlib.import_module(module).main(list(args))
    except SystemExit as exc:
        status = exc.code
    return status, capsys.readouterr().err


def test_bad_task_files_name_the_file_and_the_fix(tmp_path, capsys):
    cases = {"bad.yaml": b"workpieces: [gearbox]\n", "keys.yaml": b"workpieces: [chassis]\nspeed: 3\n",
             "broken.yaml": b"workpieces: [chassis\n", "word.yaml": b"workpieces: [chassis]\ncamera_height: high\n",
             "bool.yaml": b"workpieces: [chassis]\ncamera_height: true\n",
             "list.yaml": b"workpieces: [chassis]\ncamera_tilt_deg: [30]\n",
             "range.yaml": b"workpieces: [chassis]\ncamera_height: 5.0\n",
             "twice.yaml": b"workpieces: [chassis, chassis]\n",
             "latin1.yaml": b"workpieces: [\xe9]\n",
             "key_twice.yaml": b"workpieces: [chassis]\noccluder: true\noccluder: false\n"}
    for name, text in cases.items():
        (tmp_path / name).write_bytes(text)
        status, err = _in_process(capsys, "sim.cli", "run", str(tmp_path / name))
        assert status == 2 and name in err, err
    # PyYAML keeps the last of a key given twice without a word; and a folder is not a missing file.
    assert "the key 'occluder' is given twice, line 3" in err
    status, err = _in_process(capsys, "sim.cli", "run", str(tmp_path))
    assert status == 2 and "is a folder, not a task file" in err
    # The command itself, once: the same line and status, and no traceback.
    out = subprocess.run([sys.executable, "-m", "sim.cli", "run", str(tmp_path / "bad.yaml")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "bad.yaml" in out.stderr and "Traceback" not in out.stderr, out.stderr


def test_run_wants_at_least_one_episode(capsys):
    for count in ("0", "-2", "two", "99999999999999999999"):
        status, err = _in_process(capsys, "sim.cli", "run", "tasks/demo.yaml", "--episodes", count)
        assert status == 2 and "--episodes" in err and "from 1 to" in err, err


def test_a_negative_seed_is_a_usage_error_in_every_command(capsys):
    commands = [["sim.cli", "run", "tasks/demo.yaml"], ["sim.cli", "perceive"],
                ["psorr.cli", "decompose", "scene.pcd"], ["psorr.cli", "recognize", "models", "scene.pcd"]]
    for module, *command in commands:
        status, err = _in_process(capsys, module, *command, "--seed", "-1")
        assert status == 2 and "--seed" in err and "at least 0" in err, err


def test_grasps_draws_a_picture_per_part(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sim.cli", "grasps", "tasks/demo.yaml", "--out", str(tmp_path / "new")],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    parts = ["u_channel", "chassis", "transformer", "flanged_hub"]
    lines = out.stdout.strip().splitlines()
    assert [line.split(":")[0] for line in lines] == [f"wrote {tmp_path / 'new' / part}.png" for part in parts]
    assert all("of the upright part" in line for line in lines)  # catalog parts: grasps of the upright part
    assert all((tmp_path / "new" / f"{part}.png").stat().st_size > 5_000 for part in parts)


def test_grasps_refuses_an_out_that_is_a_file_before_the_work(tmp_path):
    (tmp_path / "taken").write_text("")
    out = subprocess.run([sys.executable, "-m", "sim.cli", "grasps", "tasks/demo.yaml", "--out",
                          str(tmp_path / "taken")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "--out" in out.stderr and "is a file; give a folder" in out.stderr, out.stderr
    assert "Traceback" not in out.stderr
