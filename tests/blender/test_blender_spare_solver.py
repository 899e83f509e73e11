"""The solver process started ahead (blender/worker.py's spare): the next bake takes it and bakes
what a process of its own would; one started otherwise is not taken; it ends on its own, with its
parent, when disabled; and a bake ends when its result comes, not when its process exits."""

from __future__ import annotations

import time

import blender_support as support  # noqa: F401  (sets BLENDER_USER_RESOURCES before bpy loads)
import bpy
import numpy as np
import pytest

from radiosity_addon.blender import worker
from radiosity_addon.blender.bake import bake_blocking


def bake_cornell():
    context = support.open_blend(support.CORNELL)
    plan = bake_blocking(context, context.scene.radiosity.bake_options(context.selected_objects))
    images = {obj.name: support.image_rgba(bpy.data.images[f"{obj.name}_lightmap"]) for obj in plan.objects}
    return plan, images


def ended_within(process, seconds: float) -> bool:
    return support.gone_within(lambda: process.poll() is not None, seconds)


@pytest.fixture(autouse=True)
def no_spare_left():
    worker.end_spare()
    yield
    worker.keep_spare(True)
    worker.end_spare()


def test_the_next_bake_takes_the_spare_and_bakes_what_a_process_of_its_own_does():
    first, cold = bake_cornell()
    assert worker.spare_process() is not None and worker.wait_for_spare(60)  # the first bake's end started it
    spare = worker.spare_process()
    second, warm = bake_cornell()
    assert second.worker.process is spare  # it solved the second bake
    assert first.worker.process is not spare
    assert cold.keys() == warm.keys()
    for name in cold:
        assert np.array_equal(cold[name], warm[name]), name
    assert second.report["counts"] == first.report["counts"]
    assert worker.spare_process() not in (None, spare)  # and a new one waits


def test_a_spare_started_with_another_command_is_ended_not_taken(monkeypatch):
    worker.start_spare()
    assert worker.wait_for_spare(60)
    stale = worker.spare_process()
    support.inject_into_solver(monkeypatch, "pass")  # the add-on's code changed since it started
    plan, _ = bake_cornell()
    assert plan.worker.process is not stale
    assert ended_within(stale, 10)


def test_the_bake_ends_when_its_result_comes_not_when_its_process_exits(monkeypatch):
    """A solver process slow to end (a driver's teardown) does not hold the bake up."""
    support.inject_into_solver(monkeypatch, """
import time
import radiosity_addon.solver_process.child as child
solve_run = child.Solve.run
def slow_to_end(self):
    solve_run(self)
    time.sleep(120)
child.Solve.run = slow_to_end
""")
    started = time.monotonic()
    plan, images = bake_cornell()
    assert time.monotonic() - started < 60
    # killed by the bake, then reaped on a thread and its files removed
    assert support.gone_within(lambda: plan.worker.process.poll() is not None
                               and not plan.worker.directory.exists(), 10)
    assert all(image[..., 3].max() > 0 for image in images.values())


def test_a_spare_ends_on_its_own_after_its_idle_time(monkeypatch):
    support.inject_into_solver(monkeypatch, "import radiosity_addon.solver_process.child as c; c.SPARE_IDLE = 0.5")
    worker.start_spare()
    spare = worker.spare_process()
    assert ended_within(spare, 30)
    assert spare.returncode == 0


def test_a_spare_ends_when_its_parent_is_gone_or_the_add_on_is_disabled():
    worker.start_spare()
    assert worker.wait_for_spare(60)
    orphan = worker.spare_process()
    orphan.stdin.close()  # what Blender's exit does to the pipe
    assert ended_within(orphan, 10)
    worker.start_spare()  # the spare above has ended: a new one
    assert worker.spare_process() is not orphan
    spare = worker.spare_process()
    from radiosity_addon.blender import ui_bake
    ui_bake.unregister()  # disabling the add-on (no bake runs)
    assert worker.spare_process() is None and ended_within(spare, 10)


def test_no_spare_when_none_is_wanted():
    worker.keep_spare(False)  # the command line: one bake, then the process ends
    bake_cornell()
    assert worker.spare_process() is None
