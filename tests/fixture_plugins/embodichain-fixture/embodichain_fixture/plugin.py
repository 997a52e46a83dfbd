"""Registrations of the fixture plugin: lazy strings only, so loading is cheap."""

import os

from embodichain_core.plugins import hookimpl


@hookimpl
def embodichain_register_tasks(register):
    register(
        "FixtureReach-v0",
        "embodichain_fixture.tasks:FixtureReachEnv",
        max_episode_steps=15,
        description="Fixture: a 3-joint arm and a cube",
    )


@hookimpl
def embodichain_register_functors(register):
    register(
        "fixture_nudge_cube",
        "embodichain_fixture.functors:fixture_nudge_cube",
        kind="event",
        category="spatial",
        description="Move a cube along x by a random offset",
    )


@hookimpl
def embodichain_register_robots(register):
    register("FixtureArm", "embodichain_fixture.tasks:FixtureArmCfg")


@hookimpl
def embodichain_register_assets(register):
    register("fixture-data", os.path.join(os.path.dirname(__file__), "data"))
