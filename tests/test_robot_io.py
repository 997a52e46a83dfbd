"""``envs/robot_io.py``: the numpy fast path (host arrays) writes and reads exactly what the
torch path does, for contiguous and scattered active joints."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from embodichain_core.envs.robot_io import RobotIO, _selector
from embodichain_core.testing.device_paths import without_host_arrays


def _pair(env, joints):
    fast = RobotIO(env.sim, env.robot, joints, env.num_envs)  # the route the backend offers: host arrays
    slow = RobotIO(without_host_arrays(env.sim), env.robot, joints, env.num_envs)  # the torch route
    return fast, slow


def test_selector_is_a_slice_only_for_one_ascending_run() -> None:
    assert _selector(np.array([3, 4, 5])) == slice(3, 6)
    assert _selector(np.array([0, 2, 4, 6])) == slice(0, 7, 2)  # interleaved position/velocity actuators
    assert _selector(np.array([4])) == slice(4, 5)
    assert isinstance(_selector(np.array([3, 5, 6])), np.ndarray)
    assert isinstance(_selector(np.array([5, 4])), np.ndarray)
    assert isinstance(_selector(np.array([2, 2])), np.ndarray)
    values = np.arange(10.0)
    for adr in ([0, 2, 4, 6], [3, 4, 5], [1, 4, 7]):
        assert np.array_equal(values[_selector(np.array(adr))], values[adr])


@pytest.mark.parametrize("joints", [[0, 1, 2, 3, 4, 5, 6], [0, 2, 5]])
def test_host_and_torch_paths_agree(make_env, joints) -> None:
    env = make_env()
    env.reset()
    fast, slow = _pair(env, joints)
    assert fast.host
    assert not slow.host
    gen = torch.Generator().manual_seed(0)
    for key in ("qpos", "qvel", "qf"):
        value = torch.rand(2, len(joints), generator=gen)
        env.sim.ctrl.zero_()
        env.sim.qfrc_applied.zero_()
        fast.write(key, value)
        after_fast = (env.sim.ctrl.clone(), env.sim.qfrc_applied.clone())
        assert bool((after_fast[0] != 0).any() or (after_fast[1] != 0).any()), key  # it wrote something
        env.sim.ctrl.zero_()
        env.sim.qfrc_applied.zero_()
        slow.write(key, value)
        assert torch.equal(env.sim.ctrl, after_fast[0]), key
        assert torch.equal(env.sim.qfrc_applied, after_fast[1]), key
    fast.write("qpos", torch.rand(len(joints), generator=gen))  # one row for every env
    assert torch.equal(env.sim.ctrl[0], env.sim.ctrl[1])
    env.sim.step(2)
    got, want = fast.observe(), slow.observe()
    for key in ("qpos", "qvel", "qf"):
        assert got[key].dtype == torch.float32
        assert torch.equal(got[key], want[key]), key
    assert float(got["qvel"].abs().sum()) > 0
    got["qpos"] += 1.0  # fresh tensors: writing one changes nothing else
    assert torch.equal(fast.observe()["qpos"], want["qpos"])


def test_a_command_of_the_wrong_width_names_both_widths(make_env) -> None:
    env = make_env()
    fast, _ = _pair(env, [0, 1, 2])
    with pytest.raises(ValueError, match=r"qpos command has 5 values per env; expected 3 .* or 9"):
        fast.write("qpos", torch.zeros(2, 5))
