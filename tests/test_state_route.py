"""``sim/backend/state_route.py``: the numpy route and the torch route to a backend's state
read and write the same values (on ``mujoco_batch``'s float64 state and on ``warp``'s float32
state), the route is picked from ``capabilities.host_arrays`` once, and no entity module
asks the backend which memory it has."""

from __future__ import annotations

import ast
from pathlib import Path
from typing import Any, Callable

import mujoco
import numpy as np
import pytest
import torch

from embodichain_core.sim.backend import conformance
from embodichain_core.sim.backend.batch_sim import BatchSim
from embodichain_core.sim.backend.state_route import DeviceRoute, HostRoute, state_route
from embodichain_core.testing.device_paths import without_host_arrays

ENTITIES = Path(__file__).resolve().parents[1] / "embodichain_core" / "sim" / "entities"


def _batch(model: mujoco.MjModel) -> Any:
    return BatchSim(model, 4)


def _warp(model: mujoco.MjModel) -> Any:
    from embodichain_core.sim.backend.warp_sim import WarpSim

    return WarpSim(model, 4)


def _exercise(route: Any) -> dict[str, Any]:
    """Writes of every index form and value type the entities use, then reads of them."""
    sim = route.sim
    sim.reset(None)
    rows = np.array([0, 2, 3])
    route.write("qpos", (rows, slice(0, 3)), np.array([[0.1, 0.2, 0.3]]) * np.arange(1, 4)[:, None])
    route.write("qpos", (torch.tensor([1]), slice(3, 7)), torch.tensor([[0.8, 0.0, 0.6, 0.0]], dtype=torch.float64))
    route.write("ctrl", (rows[:, None], np.array([[0]])), np.broadcast_to(np.array([0.7]), (3, 1)))
    route.write("qvel", (torch.arange(4)[:, None], torch.tensor([[6]])), 1.0 / 3.0)  # a number
    sim.mark_dirty(None)
    return {
        "read": route.read("qpos", (rows, slice(0, 7))).astype(np.float64),
        "read_some": route.read("qpos", (np.array([[1], [3]]), np.array([[3, 5]]))).astype(np.float64),
        "rows": route.rows("qvel", (slice(None), slice(6, 7))).clone(),
        "pose": route.pose("xpos", "xquat", (slice(None), sim.model.body("box").id)),
        "pose_some": route.pose("xpos", "xquat", (torch.tensor([1, 2]), sim.model.body("box").id)),
        "ctrl": sim.ctrl.detach().clone(),
    }


@pytest.mark.parametrize("make", [_batch, _warp], ids=["mujoco_batch", "warp"])
def test_both_routes_read_and_write_the_same_values(make: Callable[[mujoco.MjModel], Any]) -> None:
    sim = make(mujoco.MjModel.from_xml_string(conformance.SCENE))
    host, device = state_route(sim, "cpu"), state_route(without_host_arrays(sim), "cpu")
    assert isinstance(host, HostRoute)
    assert isinstance(device, DeviceRoute)
    want, got = _exercise(host), _exercise(device)
    for key, value in want.items():
        assert type(got[key]) is type(value), key
        assert np.array_equal(np.asarray(got[key]), np.asarray(value)), (key, got[key], value)
    assert want["rows"].dtype == torch.float32
    assert want["pose"].shape == (4, 7)
    assert np.allclose(want["read"][2, :3], [0.3, 0.6, 0.9], atol=1e-6)  # the writes landed
    assert np.allclose(want["read"][0, 3:], sim.model.qpos0[3:7])  # rows not written keep theirs
    assert np.allclose(want["read_some"][0], [0.8, 0.6], atol=1e-6)
    assert float(want["ctrl"][1, 0]) == 0.0
    assert np.allclose(want["ctrl"][[0, 2, 3], 0].double().numpy(), 0.7)


def test_the_warp_backend_without_host_arrays_has_no_numpy_stand_in() -> None:
    from embodichain_core.sim.backend.warp_device import cpu_device_route
    from embodichain_core.sim.backend.warp_sim import WarpSim

    model = mujoco.MjModel.from_xml_string(conformance.SCENE)
    with cpu_device_route():
        sim = WarpSim(model, 2)
    assert not sim.capabilities.host_arrays
    with pytest.raises(AttributeError, match=r"no host arrays .*sim\.tensors"):
        sim.arrays  # noqa: B018
    assert sim.tensors["qpos"] is sim.qpos
    assert isinstance(state_route(sim, "cpu"), DeviceRoute)
    assert WarpSim(model, 2).capabilities.host_arrays  # outside the block: the CPU's numpy views
    conformance.check_views(lambda m, n: WarpSim(m, n, host_arrays=False))


def _host_checks(path: Path) -> list[str]:
    """Where ``path`` reaches past its route: ``sim.arrays``, ``capabilities``, ``_host_reads``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Attribute) and node.attr in ("arrays", "capabilities", "_host_reads"):
            found.append(f"{path.name}:{node.lineno} .{node.attr}")
    return found


def test_no_entity_asks_the_backend_which_memory_it_has() -> None:
    modules = sorted(ENTITIES.glob("*.py"))
    assert len(modules) >= 6
    found = [hit for path in modules for hit in _host_checks(path)]
    assert found == [], "entities go through self.state_route, chosen once: " + ", ".join(found)
    probe = ENTITIES.parent / "backend" / "state_route.py"
    assert _host_checks(probe), "the scan finds nothing even where the route is chosen"
