"""The deep zoo bugs (benchmarks/zoo/deep.py) are wrong inside their region and right outside it."""

from __future__ import annotations

import json
import math
import signal
from dataclasses import asdict, replace
from typing import Any

import pytest

import native
import python_impl
from benchmarks import bench_deep, deep_stats
from benchmarks.bench_zoo import Run
from benchmarks.zoo import DEEP, STATEFUL, UNTUNED, ZOO, deep
from fuzzer.execution.records import UNCOUNTED, Comparison
from fuzzer.execution.session import RunConfig, Session
from fuzzer.execution.tolerance import default_tolerance
from fuzzer.generation.corpus import tutorial_seeds
from fuzzer.generation.spacefill import joint_target_step
from fuzzer.input.testcase import TestCase
from python_impl.trajectory import plan_trajectory
from robot_api import robots

ANNO = robots.resolve("probot_anno")
SECOND = [-0.4, 0.6, 0.9, -0.3, 0.7, -0.5]


def _gap(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    return max(abs(x - y) for x, y in zip(a, b, strict=True))


@pytest.fixture(scope="module")
def reference() -> python_impl.RobotModel:
    return native.RobotModel(ANNO)


def _fk_gap(variant: object, values: list[float], reference: python_impl.RobotModel) -> float:
    """The largest gap in position (m) or quaternion component between the variant and native."""
    mine = variant.RobotModel(ANNO).forward_kinematics(values)  # type: ignore[attr-defined]
    theirs = reference.forward_kinematics(values)
    return _gap((*mine.position, *mine.orientation), (*theirs.position, *theirs.orientation))


BAND_START = -2.007 + 0.6173 * 4.014  # joint_2's limits are about +-2.007


@pytest.mark.parametrize(
    ("name", "inside", "outside"),
    [
        (
            "narrow_band",
            [0.1, BAND_START + 0.002, 0.3, 0.0, 0.5, 0.0],
            [0.1, BAND_START - 0.01, 0.3, 0.0, 0.5, 0.0],
        ),
        (
            "joint_relation",
            [0.9, 0.2, 0.9 - (math.sqrt(2) - 1) + 2e-4, 0, 0.5, 0],
            [0.9, 0.2, 0.3, 0, 0.5, 0],
        ),
        ("calibration_entry", [0.0, 0.2, 1.37, 0.0, 0.5, 0.0], [0.0, 0.2, 1.36, 0.0, 0.5, 0.0]),
        ("small_angle_wrist", [0.0, 0.2, 0.5, 0.3, 1e-3, 0.0], [0.0, 0.2, 0.5, 0.3, 0.0, 0.0]),
    ],
)
def test_fk_faults_only_inside_their_band(
    name: str, inside: list[float], outside: list[float], reference: python_impl.RobotModel
) -> None:
    variant = getattr(deep, name)
    assert _fk_gap(variant, inside, reference) > 1e-5
    assert _fk_gap(variant, outside, reference) < 1e-9


def _search(predicate: object, reference: python_impl.RobotModel) -> list[float]:
    """A configuration whose tool pose satisfies ``predicate`` (a seeded scan of joint_1)."""
    for i in range(200000):
        q = [-math.pi + i * 2 * math.pi / 200000, 0.3, 0.6, 0.0, 0.7, 0.0]
        if predicate(reference.forward_kinematics(q).position):  # type: ignore[operator]
            return q
    raise AssertionError("no configuration found")


def test_computed_branch_and_atan2_band(reference: python_impl.RobotModel) -> None:
    q = _search(lambda p: 0.1236 <= p[0] < 0.1242, reference)
    assert _fk_gap(deep.computed_branch, q, reference) > 1e-5
    assert _fk_gap(deep.computed_branch, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], reference) < 1e-9
    q = _search(lambda p: 2.002 < math.atan2(p[1], p[0]) < 2.008, reference)
    assert _fk_gap(deep.atan2_quadrant, q, reference) > 1e-5
    assert _fk_gap(deep.atan2_quadrant, [0.0, 0.3, 0.6, 0.0, 0.7, 0.0], reference) < 1e-9


def test_wrap_past_pi_needs_a_revolute_joint_beyond_pi() -> None:
    ur5 = robots.resolve("ur5")
    model = deep.wrap_past_pi.RobotModel(ur5)
    group = deep.wrap_past_pi.MoveGroup(model)
    group.set_joint_value_target([4.02, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert group.get_joint_value_target()[0] == pytest.approx(4.02 - 2 * math.pi)
    group.set_joint_value_target([3.9, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert group.get_joint_value_target()[0] == 3.9


def test_per_joint_band_moves_a_target_only_inside_its_band() -> None:
    model = deep.per_joint_band.RobotModel(ANNO)
    group = deep.per_joint_band.MoveGroup(model)
    for joint in range(6):
        target = [0.2] * 6
        target[joint] = deep.CORRECTED_FROM + 1e-5
        group.set_joint_value_target(target)
        assert group.get_joint_value_target()[joint] == pytest.approx(target[joint] + deep.SHIFT)
    for outside in (deep.CORRECTED_FROM - 1e-9, deep.CORRECTED_TO, 0.8613, 0.8614):
        group.set_joint_value_target([outside] * 6)
        assert group.get_joint_value_target() == [outside] * 6


def test_ik_seed_band_only_from_seeds_in_its_band(reference: python_impl.RobotModel) -> None:
    model = deep.ik_seed_band.RobotModel(ANNO)
    goal = reference.forward_kinematics([0.5, 0.3, 0.6, 0.0, 0.7, 0.0])
    wrong = model.inverse_kinematics(goal, [0.305, 0.3, 0.6, 0.0, 0.7, 0.0])
    assert wrong.joint_values[0] == 0.305  # "success" at the seed
    right = model.inverse_kinematics(goal, [0.2, 0.3, 0.6, 0.0, 0.7, 0.0])
    assert str(right.status) == "success" and right.joint_values[0] == pytest.approx(0.5, abs=1e-5)
    assert model.inverse_kinematics(goal).joint_values[0] != 0.0  # the default seed is home: no fault


def test_ik_seed_band_answers_from_its_band_without_solving(monkeypatch, reference) -> None:  # type: ignore[no-untyped-def]
    """The fault returns before any Newton-Raphson iteration (a seed in the band costs no
    solve), and after the twin's own argument checks: a bad pose or seed is the twin's error."""
    from python_impl import kinematics
    from robot_api.errors import InvalidInputError

    model = deep.ik_seed_band.RobotModel(ANNO)
    goal = reference.forward_kinematics([0.5, 0.3, 0.6, 0.0, 0.7, 0.0])

    def no_solve(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError("solved from a seed in the band")

    monkeypatch.setattr(kinematics, "ik", no_solve)
    answer = model.inverse_kinematics(goal, [0.305, 0.3, 0.6, 0.0, 0.7, 0.0])
    assert (str(answer.status), answer.joint_values) == ("success", (0.305, 0.3, 0.6, 0.0, 0.7, 0.0))
    twin = python_impl.RobotModel(ANNO)
    for pose, seed in (
        (goal, [0.305, math.nan, 0.6, 0.0, 0.7, 0.0]),
        (goal, [0.305, 0.3]),
        (((math.inf, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)), [0.305, 0.3, 0.6, 0.0, 0.7, 0.0]),
    ):
        with pytest.raises(InvalidInputError) as mine:
            model.inverse_kinematics(pose, seed)
        with pytest.raises(InvalidInputError) as theirs:
            twin.inverse_kinematics(pose, seed)
        assert str(mine.value) == str(theirs.value)


# -- the deep scenario bugs: each needs a call sequence, and the tutorial scripts miss them ----------


def _scenario(target: str) -> Session:
    return Session.open(
        RunConfig(
            op="scenario",
            robot="probot_anno",
            targets=("native", target),
            tolerance=default_tolerance("scenario"),
        )
    )


def _judge(target: str, steps: list[dict[str, Any]]) -> Comparison:
    session = _scenario(target)
    evaluation = session.evaluator().evaluate(
        TestCase(session.config.message_type, {"steps": steps}, 0, "t", ("t",), 1)
    )
    assert evaluation.verdict == "evaluated", evaluation.reason
    return evaluation.comparison


def _call(topic: str) -> dict[str, Any]:
    return {"topic": topic, "msg": {}}


def _factor(topic: str, value: float) -> dict[str, Any]:
    return {"topic": topic, "msg": {"data": value}}


def _target(values: list[float]) -> dict[str, Any]:
    return joint_target_step(values, [f"joint_{i}" for i in range(1, 7)])


def _in_start_band(share: float) -> float:
    """joint_2 (limits about +-2.007) at ``share`` of plan_start_band's band (0 its start, 1 its end)."""
    lim = python_impl.RobotModel(ANNO).joint_limits[1]
    width = lim.upper - lim.lower
    return lim.lower + (deep.START_BAND_AT + 0.001 * share) * width


SWITCH_SCALING = 0.2
"""Both scaling factors of the profile-switch scripts: on PROBOT Anno (every joint 3 rad/s,
``ACCELERATION_LIMIT`` 1) the ratio A / v**2 of a move is then max |delta| / 1.8."""


def _switch_script(ratio: float) -> list[dict[str, Any]]:
    move = 9.0 * SWITCH_SCALING * ratio  # joint_1's displacement from home, the largest one
    return [
        _factor("/velocity_scaling", SWITCH_SCALING),
        _factor("/acceleration_scaling", SWITCH_SCALING),
        _target([move, 0.1, 0.2, 0.1, 0.4, 0.2]),
        _call("/plan"),
    ]


DEEP_SCRIPTS = {
    "execute_skips_start_check": (
        [
            _target([0.5, 0.3, 0.2, 0.1, 0.4, 0.2]),
            _call("/plan"),
            _target(SECOND),
            _call("/go"),
            _call("/execute"),
        ],
        # the tutorials' order: the plan executed at once, so it starts where the arm is
        [
            _target([0.5, 0.3, 0.2, 0.1, 0.4, 0.2]),
            _call("/plan"),
            _call("/execute"),
            _target(SECOND),
            _call("/go"),
        ],
        "execute.status",
    ),
    "plan_start_band": (
        [
            _target([0.1, _in_start_band(0.5), 0.3, 0.0, 0.5, 0.0]),
            _call("/go"),
            _target(SECOND),
            _call("/plan"),
        ],
        [
            _target([0.1, _in_start_band(1.01), 0.3, 0.0, 0.5, 0.0]),
            _call("/go"),
            _target(SECOND),
            _call("/plan"),
        ],
        "plan.trajectory",
    ),
    "profile_switch_band": (_switch_script(1.0005), _switch_script(1.0011), "plan.trajectory"),
}
"""Per deep scenario bug: a script that shows it, a near miss that does not, the field reported."""


@pytest.mark.parametrize("name", sorted(DEEP_SCRIPTS))
def test_a_deep_scenario_fault_shows_in_its_script_and_not_in_the_near_miss(name: str) -> None:
    shows, near_miss, field = DEEP_SCRIPTS[name]
    comparison = _judge(f"benchmarks.zoo.deep:{name}", shows)
    assert comparison.divergent and comparison.kind not in UNCOUNTED, comparison
    assert comparison.field.startswith(field), comparison
    assert not _judge(f"benchmarks.zoo.deep:{name}", near_miss).divergent
    assert not _judge("python", shows).divergent  # the unmodified twin agrees on both
    assert not _judge("python", near_miss).divergent


def test_the_profile_ratio_is_the_switch_of_the_twin_s_profile() -> None:
    """Below 1 the twin's plan never reaches its cruise speed, above 1 it does (then holds it)."""
    limits = python_impl.RobotModel(ANNO).joint_limits
    home = [0.0] * 6
    for ratio in (0.9, 0.999, 1.001, 1.1):
        goal = [9.0 * SWITCH_SCALING * ratio, 0.1, 0.2, 0.1, 0.4, 0.2]
        assert deep.profile_ratio(limits, home, goal, SWITCH_SCALING, SWITCH_SCALING) == pytest.approx(ratio)
        speed = plan_trajectory(limits, home, goal, SWITCH_SCALING, SWITCH_SCALING).velocities[:, 0]
        cruise = 3.0 * SWITCH_SCALING
        assert (abs(speed.max() - cruise) < 1e-12) == (ratio > 1), ratio
    assert deep.profile_ratio(limits, home, home, 1.0, 1.0) == 0.0  # no move


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_tutorial_scripts_do_not_show_the_deep_scenario_faults(seed: int) -> None:
    """What the campaign starts from misses them, so the table measures the search."""
    for name in DEEP_SCRIPTS:
        session = _scenario(f"benchmarks.zoo.deep:{name}")
        evaluator = session.evaluator()
        for case in tutorial_seeds(session, seed):
            comparison = evaluator.evaluate(case).comparison
            assert not comparison.divergent or comparison.kind in UNCOUNTED, (name, case.sequence, comparison)


# -- the statistics of benchmarks/bench_deep.py ---------------------------------------------------


def _run(engine: str, seed: int, at: float | None, bug: str = "narrow_band", op: str = "fk") -> Run:
    return Run(bug, engine, seed, 10.0, at, 1 if at is not None else 0, 100, 10.0, op, 0)


def test_a12_and_censoring() -> None:
    assert deep_stats.a12([1.0, 2.0], [3.0, 4.0]) == 1.0  # the first always sooner
    assert deep_stats.a12([3.0], [3.0]) == 0.5
    runs = [_run("full", 0, 2.0), _run("full", 1, None), _run("full", 2, 50.0)]
    assert deep_stats.censored(runs, 10.0) == [2.0, 10.0, 10.0]


def test_compare_verdicts() -> None:
    fast, slow = [1.0 + 0.1 * i for i in range(10)], [8.0 + 0.1 * i for i in range(10)]
    p, effect, verdict = deep_stats.compare(fast, slow)
    assert p < 0.05 and effect == 1.0 and verdict == "faster"
    assert deep_stats.compare(slow, fast)[2] == "slower"
    assert deep_stats.compare([10.0] * 5, [10.0] * 5) == (1.0, 0.5, "tie")
    assert deep_stats.compare([1.0, 9.0, 2.0], [8.0, 1.5, 3.0])[2] == "tie"


def test_survival_and_markdown() -> None:
    runs = [_run("full", i, 1.0 + i) for i in range(4)] + [_run("uniform", i, None) for i in range(4)]
    times, share = deep_stats.survival([r for r in runs if r.engine == "full"], 10.0, points=11)
    assert times[0] == 0.0 and times[-1] == 10.0
    assert share[0] == 0.0 and share[-1] == 1.0 and share == sorted(share)
    mode = deep_stats.Mode(("narrow_band",), 4, 10.0, ("full", "uniform"))
    text = deep_stats.markdown(runs, mode, "cmd")
    row = next(line for line in text.splitlines() if line.startswith("| narrow_band"))
    assert "(4/4)" in row and "- (0/4)" in row and "faster" in row
    assert "tabulated from a results file" in text  # how many ran at once is not known
    assert "1 run at a time" in deep_stats.markdown(runs, mode, "cmd", jobs=1)
    assert (
        'Corrected for the table\'s 1 comparisons (Bonferroni: p < 0.05/1 = 0.05): 1 of its 1 "faster"'
        in text
    )
    assert "2 runs at a time" in deep_stats.markdown(runs, mode, "cmd", jobs=2)
    late = [_run("full", 0, 2.0), _run("full", 1, 12.0)]  # the second past the 10-s budget
    table = deep_stats.markdown(late, mode, "cmd").splitlines()
    row = next(ln for ln in table if ln.startswith("| narrow_band"))
    assert "(1/2)" in row  # a detection after the budget is not one within it


def test_the_median_cell_is_over_all_the_trials() -> None:
    """Detections at 1..7 s and three misses: the median of the ten trials is 5.5 s (the cell
    said 4.0, the upper middle of the seven detections alone); 1..10 s: 5.5 (it said 6.0)."""
    mode = deep_stats.Mode(("narrow_band",), 10, 10.0, ("full",))

    def cell(runs: list[Any]) -> str:
        table = deep_stats.markdown(runs, mode, "cmd").splitlines()
        return next(ln for ln in table if ln.startswith("| narrow_band")).split("|")[2].strip()

    seven = [_run("full", i, float(i + 1)) for i in range(7)] + [_run("full", 7 + i, None) for i in range(3)]
    assert cell(seven) == "5.5 (7/10)"
    assert cell([_run("full", i, float(i + 1)) for i in range(10)]) == "5.5 (10/10)"
    half = [_run("full", i, 1.0) for i in range(5)] + [_run("full", 5 + i, None) for i in range(5)]
    assert cell(half) == ">10 (5/10)"


def test_a_verdict_stands_corrected_only_below_alpha_over_the_comparisons() -> None:
    """60-88 comparisons per table: at p < 0.05 each, one true tie in 40 comes out "slower" by
    chance. Bonferroni keeps a verdict at p < 0.05 / the table's comparisons."""
    tests = [(0.0001, "faster"), (0.008, "faster"), (0.006, "slower")] + [(0.5, "tie")] * 7
    line = deep_stats.corrected(tests)  # threshold 0.005
    assert '1 of its 2 "faster" and 0 of its 1 "slower" verdicts stand' in line
    assert '2 of its 2 "faster" and 1 of its 1 "slower"' in deep_stats.corrected(tests[:3])  # 0.0167
    assert deep_stats.corrected([]) == "No comparisons to correct."


def test_the_search_table_takes_the_start_up_out() -> None:
    """A slower start-up with a quicker search: slower from the process start, faster from the
    first input (the second table), and each engine's median start-up shown."""
    full = [replace(_run("full", i, 2.0 + 0.01 * i), first_input=1.9) for i in range(6)]
    other = [replace(_run("uniform", i, 1.5 + 0.01 * i), first_input=1.0) for i in range(6)]
    assert full[0].search_time == pytest.approx(0.1) and _run("full", 0, None).search_time is None
    assert deep_stats.censored_search([*full[:1], _run("full", 1, 3.0)], 10.0) == [pytest.approx(0.1), 10.0]
    mode = deep_stats.Mode(("narrow_band",), 6, 10.0, ("full", "uniform"))
    text = deep_stats.markdown([*full, *other], mode, "cmd")
    first, second = (line for line in text.splitlines() if line.startswith("| narrow_band"))
    assert "slower" in first and "faster" in second
    assert "| 1.90 | 1.00 |" in second


def test_the_quick_mode_runs_and_the_sweep_finds_the_narrower_band(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``bench_deep --mode quick`` (what CI runs of issue 11's statistics): 2 deep bugs x (full,
    uniform) x 2 trials x 10 s. The full engine's batched sweeps meet a band 1e-5 of joint_2's
    range wide in every trial (about 2 hits a second expected); uniform sampling at its ~2,000
    inputs a second expects one hit in 50 s, so it is not asserted."""
    runs = bench_deep.main(["--mode", "quick", "--jobs", "2", "--results", str(tmp_path)])
    assert {(r.bug, r.engine) for r in runs} == {
        (bug, engine) for bug in ("narrower_band", "computed_branch") for engine in ("full", "uniform")
    }
    # a trial ends by itself (0, or 1 with a divergence), or killed at its first detection
    stopped = [r for r in runs if r.returncode == -signal.SIGKILL]
    assert all(r.returncode in (0, 1) or r in stopped for r in runs), [
        (r.bug, r.engine, r.returncode) for r in runs
    ]
    assert all(r.detected_at is not None and r.first_input is not None for r in stopped)
    swept = [r for r in runs if r.bug == "narrower_band" and r.engine == "full"]
    assert len(swept) == 2 and all(r.detected_at is not None and r.detected_at < 10.0 for r in swept)
    assert (tmp_path / "deep-quick.json").is_file() and (tmp_path / "deep-quick.png").is_file()
    assert all(r.first_input is not None and 0.0 < r.first_input < 10.0 for r in runs)  # start-up logged
    # libFuzzer's seed of each full-engine trial is kept: -seed=1's, and the one drawn for -seed=0
    # (libFuzzer's "draw one"), which -seed=N --seed=0 repeats; the baseline runs no libFuzzer
    for r in runs:
        kept = r.libfuzzer_seed
        wanted = kept is None if r.engine == "uniform" else kept == 1 if r.seed == 1 else (kept or 0) > 1
        assert wanted, (r.bug, r.engine, r.seed, kept)


def test_an_earlier_results_file_is_tabulated_again(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``--from-json`` re-tabulates a deep-<mode>.json (its bugs, engines, trials, budget) and
    names a file that is not one instead of raising."""
    import json
    from dataclasses import asdict

    runs = [replace(_run("full", i, 1.0 + i), first_input=0.5) for i in range(3)]
    runs += [replace(_run("uniform", i, None), first_input=0.4) for i in range(3)]
    source = tmp_path / "in.json"
    source.write_text(json.dumps([{**asdict(r), "future_field": 1} for r in runs]))
    again = bench_deep.main(["--mode", "short", "--from-json", str(source), "--results", str(tmp_path)])
    assert again == runs and (tmp_path / "deep-short.png").is_file()
    assert not (tmp_path / "deep-short.json").exists()  # the source is not copied over
    for bad in ("{}", "[]", "[1]", '[{"bug": "x"}]', "not json"):
        source.write_text(bad)
        with pytest.raises(SystemExit) as exit_info:
            bench_deep.main(["--from-json", str(source), "--results", str(tmp_path)])
        assert exit_info.value.code == 2


def test_the_zoo_mode_runs_the_shallow_zoo_and_marks_what_has_no_scenario_op(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``--mode zoo``: the 23 shallow zoo bugs in the zoo's order, with a section of its own; a
    scenario bug's row says 'n/a' for the engines without a scenario op, and the plot copes."""
    mode = bench_deep.MODES["zoo"]
    assert mode.bugs == tuple(b.name for b in ZOO) and (mode.trials, mode.budget) == (10, 10.0)
    assert mode.engines == ("full", "libfuzzer", "paper", "hypothesis", "uniform")
    assert list(bench_deep.BUGS) == [b.name for b in (*DEEP, *ZOO, *UNTUNED)]
    assert sorted(["silent_clamp", "tight_relation", "cached_pose"], key=bench_deep._bug_order) == [
        "tight_relation",
        "silent_clamp",
        "cached_pose",
    ]
    assert bench_deep.SECTIONS["zoo"][0] == ("<!-- bench_deep_zoo:begin -->", "<!-- bench_deep_zoo:end -->")
    scenario = STATEFUL[0].name
    runs = [_run(e, i, 1.0 + i, "silent_clamp", "move") for e in mode.engines for i in range(3)]
    runs += [_run(e, i, 2.0 + i, scenario, "scenario") for e in ("full", "libfuzzer") for i in range(3)]
    runs = [replace(r, first_input=0.5, returncode=0) for r in runs]
    small = deep_stats.Mode(("silent_clamp", scenario), 3, 10.0, mode.engines)
    # the header says trials stopped at detection only when some were (an older results file: no)
    assert "A trial stops" not in deep_stats.markdown(runs, small, "cmd")
    runs = [replace(r, returncode=-9) for r in runs]
    text = deep_stats.markdown(runs, small, "cmd")
    assert "A trial stops at its first detection" in text
    first, second = (line for line in text.splitlines() if line.startswith(f"| {scenario} "))
    cells = first.strip("|").split("|")
    assert [c.strip() for c in cells[1:6]] == ["3.0 (3/3)", "3.0 (3/3)", *["n/a (no trials)"] * 3]
    assert [c.strip() for c in cells[7:]] == ["n/a"] * 3  # no verdict against paper, hypothesis, uniform
    assert second.count("n/a") == 6 and "| 0.50 | 0.50 |" in second  # no start-up, no search verdict
    move = next(line for line in text.splitlines() if line.startswith("| silent_clamp "))
    assert "n/a" not in move
    deep_stats.plot(runs, small, tmp_path / "zoo.png")
    assert (tmp_path / "zoo.png").is_file()


def test_the_full_and_short_tables_have_sections_of_their_own(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """``make bench``'s 60-s table (``--mode full``) does not replace ``make bench-deep``'s
    10-s one (``--mode short``): each mode writes between its own marks."""
    written: list[tuple[str, str]] = []

    def replace_section(text: str, marks: tuple[str, str], title: str) -> None:
        written.append(marks)

    monkeypatch.setattr(bench_deep, "replace_section", replace_section)
    monkeypatch.setattr(bench_deep, "RESULTS", tmp_path)  # the plot goes there, not into the tree
    for mode in ("full", "short"):
        table = bench_deep.MODES[mode]
        source = tmp_path / f"runs-{mode}.json"
        runs = [
            Run(bug, engine, seed, table.budget, 1.0 + seed, 1, 100, table.budget, bench_deep.BUGS[bug].op, 0)
            for bug in table.bugs
            for engine in table.engines
            for seed in range(table.trials)
        ]
        source.write_text(json.dumps([asdict(r) for r in runs]))
        bench_deep.main(["--mode", mode, "--from-json", str(source), "--write-md"])
    assert written == [
        ("<!-- bench_deep_full:begin -->", "<!-- bench_deep_full:end -->"),
        ("<!-- bench_deep:begin -->", "<!-- bench_deep:end -->"),
    ]
    # a file that is not the table's (one bug of it, three trials), or a plot elsewhere: refused
    small = tmp_path / "small.json"
    small.write_text(
        json.dumps([asdict(_run(e, i, 1.0, "narrow_band")) for e in ("full", "uniform") for i in range(3)])
    )
    with pytest.raises(SystemExit):
        bench_deep.main(["--mode", "short", "--from-json", str(small), "--write-md"])
    with pytest.raises(SystemExit):
        bench_deep.main(
            ["--mode", "short", "--from-json", str(source), "--write-md", "--results", str(tmp_path / "x")]
        )
    assert len(written) == 2
