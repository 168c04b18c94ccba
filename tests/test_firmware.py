"""The controllers build for a Cortex-M4F with the project's warnings as errors, and their cost harness runs."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import _missing, require_tool

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("firmware_bench", ROOT / "benchmarks" / "firmware.py")
fw = importlib.util.module_from_spec(spec)
sys.modules["firmware_bench"] = fw
spec.loader.exec_module(fw)


@pytest.mark.slow
def test_every_controller_cross_compiles_for_cortex_m4f(tmp_path):
    require_tool("arm-none-eabi-gcc")
    sizes = fw.arm_sizes(tmp_path)
    base = sizes.pop("none")
    assert set(sizes) == set(fw.harness_names())
    for name, (flash, ram) in sizes.items():
        assert flash > base[0], f"{name} adds no code: the harness does not call it"
        # the flash budget of one controller (libm functions included): 40 kB leaves 24 kB of a 64 kB-flash ESC
        # microcontroller (the STM32F051/G071 class of AM32 ESCs) to the rest of its firmware. Raised from 32 kB on
        # 2026-11-26, when the sinusoidal controller with both observers, its I/f start-up, the catch of a turning
        # rotor and the alignment's resistance estimate reached 32,464 B (sine_obs 32,644 B)
        assert flash - base[0] < 40_000, f"{name}: {flash - base[0]} B of flash"
        assert ram >= base[1]


def test_every_registered_controller_is_in_the_firmware_harness():
    import bldclab._core as core

    registered = set(core.core().controllers) - {"table"}  # table replays host arrays: a simulation driver
    assert registered <= set(fw.harness_names()), registered - set(fw.harness_names())
    assert registered <= set(fw.cost_names()), registered - set(fw.cost_names())
    # ... and measured in closed loop (core/firmware/replay.c's targets; firmware.py checks they exist)
    closed = {c.registry for c in fw.CLOSED_LOOP.values()}
    assert registered <= closed, registered - closed
    assert all(c.runs for c in fw.CLOSED_LOOP.values())


@pytest.mark.slow
def test_closed_loop_replay_is_the_closed_loop_and_counts_every_step():
    require_tool("valgrind")
    require_tool("cc")
    try:
        res = fw.closed_loop_counts(["sixstep"], scale=0.1)["sixstep"]  # 15 ms start-up, 5 ms at each speed
    except RuntimeError as exc:
        if "callgrind.h" not in str(exc):
            raise
        _missing(f"valgrind's callgrind.h is missing (the valgrind package installs it): {exc}")
    assert [r.label for r in res.runs] == [fw.START, fw.HALF, fw.FULL]
    assert [len(r.steps) for r in res.runs] == [420, 140, 140]  # one dump with one step call per sample
    for r in res.runs:
        assert r.identical, r.info  # the -O2 replay reproduces the closed loop's outputs bit for bit
        assert r.info["steps"] == len(r.steps)
        assert 300 < min(r.steps) <= r.mean <= r.worst < 20_000, (r.label, min(r.steps), r.mean, r.worst)
    assert res.worst == max(max(r.steps) for r in res.runs)
    assert res.mean == pytest.approx(sum(sum(r.steps) for r in res.runs) / 700)


@pytest.mark.slow
def test_cost_harness_runs_every_scenario(tmp_path):
    require_tool("cc")
    exe = tmp_path / "cost"
    subprocess.run(["cc", "-O2", "-I", str(fw.CTRL / "include"), str(fw.CORE / "firmware" / "cost.c"),
                    str(fw.CORE / "firmware" / "targets.c"), *map(str, fw.controller_sources()), "-lm", "-o", str(exe)],
                   check=True)
    for name in fw.cost_names():
        for sc in fw.SCENARIOS:
            out = subprocess.run([str(exe), name, sc, "2000"], check=True, capture_output=True, text=True).stdout
            assert out.startswith(f"{name} {sc} 2000")


def test_make_firmware_cross_compiles_exactly_the_ctrl_half(tmp_path):
    require_tool("arm-none-eabi-gcc")
    proc = subprocess.run(["make", "-C", str(fw.CORE), "firmware", f"FW_BUILD={tmp_path}"], capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    built = {p.stem for p in tmp_path.glob("*.o")}
    assert built == {p.stem for p in fw.controller_sources()}
    assert not built & {p.stem for p in (fw.CORE / "host" / "src").glob("*.c")}


def test_a_target_without_its_harness_branch_fails_the_build(tmp_path):
    require_tool("arm-none-eabi-gcc")
    cmd = ["arm-none-eabi-gcc", *fw.ARM, *fw.WARN, "-DBC_FW_NOT_A_CONTROLLER", f"-I{fw.CTRL / 'include'}", "-c",
           str(fw.CORE / "firmware" / "harness.c"), "-o", str(tmp_path / "x.o")]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode != 0 and "targets.txt" in proc.stderr
