"""Every stage of a solve and of the lightmaps reports its progress, with the time left of all the
stages ahead (core.timing.StagePlan): a bar that moves from the first second on."""

import time

import numpy as np
import pytest

from radiosity_addon.core import LightmapSettings, SolveSettings, bake_lightmaps, lightmap_seconds, lightmap_sizes, solve
from radiosity_addon.core.timing import StagePlan, pulse
from scenes import grid_triangles, sphere_triangles, triangle_scene


def test_a_plan_reports_the_predicted_share_done_and_the_rest_scaled_by_the_stages_done():
    calls = []
    plan = StagePlan(lambda fraction, message, details: calls.append((fraction, message, details)),
                     {"first": 1.0, "second": 3.0})
    with plan.stage("first", "one"):
        time.sleep(0.2)
    assert calls[0][0] == 0.0 and calls[0][2]["eta"] == pytest.approx(4.0, rel=0.01)
    with plan.stage("second", "two"):
        plan.report(0.5, "half way")
    # the first stage took a fifth of its prediction: the second is scaled alike (held to a quarter at
    # least); half way through it by its own count but at once, its rest is the longer of its share's
    # rest (0.375 s) and its scaled prediction less the time gone (0.75 s): the estimate errs long
    fraction, _, details = calls[-1]
    assert fraction == pytest.approx((1.0 + 0.5 * 3.0) / 4.0)
    assert details["eta"] == pytest.approx(3.0 * 0.25, rel=0.05)
    assert details["stage"] == "second" and details["stage_fraction"] == 0.5 and details["stage_eta"] is None
    with plan.stage("second", "again"):
        plan.report(0.2, "with its own estimate", {"eta": 7.0})
    assert calls[-1][2]["eta"] == 7.0 and calls[-1][2]["stage_eta"] == 7.0


def test_stages_predicted_in_milliseconds_do_not_scale_the_rest_and_a_stage_that_estimates_itself_is_waited_for():
    calls = []
    plan = StagePlan(lambda fraction, message, details: calls.append(details), {"tiny": 0.001, "shots": 70.0,
                                                                                 "after": 2.0})
    with plan.stage("tiny", "a call's overhead"):
        time.sleep(0.1)  # a hundred times its prediction: no evidence of this machine's speed
    assert plan.speed == 1.0
    with plan.stage("shots", "shooting", estimates_itself=True):
        plan.report(0.3, "shot 32")  # a cost model's 70 s is not shown: the time left is not known yet
        assert calls[-1]["eta"] is None and calls[-1]["stage"] == "shots"
        plan.report(0.6, "shot 512", {"eta": 9.0})
        assert calls[-1]["eta"] == pytest.approx(9.0 + 2.0)
        plan.report(0.7, "shot 544")  # once it has estimated, a report without one falls back on the plan
        assert calls[-1]["eta"] is not None


def test_a_long_loop_pulses_the_running_stage_by_the_time_gone():
    calls = []
    plan = StagePlan(lambda fraction, message, details: calls.append(fraction), {"long": 10.0})
    pulse()  # outside any stage: nothing
    assert calls == []
    with plan.stage("long", "working"):
        for _ in range(3):
            time.sleep(0.55)
            pulse()
    assert len(calls) == 4 and calls == sorted(calls) and 0.1 < calls[-1] < 0.3


def test_every_stage_of_a_dense_scenes_solve_and_lightmaps_reports(gpu):
    floor, floor_uv = grid_triangles([-1, -1, 0], [2, 0, 0], [0, 2, 0], 60)
    ball, ball_uv = sphere_triangles([0, 0, 0.4], 0.35, 24)
    scene = triangle_scene([("floor", floor, floor_uv, 0.5, 0.0), ("ball", ball, ball_uv, 0.6, 0.0)],
                           lights=[{"type": "sun", "color": [1, 1, 1], "direction": [0.2, 0.1, -1], "strength": 3}],
                           world=[0.2, 0.3, 0.4])
    reports = []
    record = lambda fraction, message, details: reports.append((fraction, details))  # noqa: E731
    solution = solve(scene, SolveSettings.preset("draft"), progress=record, gpu=gpu)
    stages = [details["stage"] for _, details in reports]
    assert {"cluster", "analyse", "refine", "method"} <= set(stages)
    fractions = [fraction for fraction, _ in reports]
    assert fractions == sorted(fractions) and fractions[-1] <= 1.0
    assert all(details["eta"] >= 0 for _, details in reports)
    settings = LightmapSettings.preset("draft")
    lightmap_reports = []
    bake_lightmaps(scene, solution, settings, gpu=gpu,
                   progress=lambda fraction, message, details: lightmap_reports.append(details))
    assert lightmap_reports and all(details["stage"] == "lightmaps" for details in lightmap_reports)
    assert lightmap_reports[0]["eta"] == pytest.approx(lightmap_seconds(scene, lightmap_sizes(scene, settings), settings))
    assert np.isfinite(lightmap_reports[0]["eta"]) and lightmap_reports[0]["eta"] > 0
