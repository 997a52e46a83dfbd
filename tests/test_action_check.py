"""``env.step`` checks the action once at the boundary: one clear ``TypeError`` or
``ValueError`` naming the expected shape and the action space, never a torch error
from inside an action term; numpy, lists and 1-D actions follow the documented rule."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from core_testlib import ARM_ACTIVE, ARM_DOF

from embodichain_core.envs.action_check import ActionChecker
from embodichain_core.managers import ActionTermCfg
from embodichain_core.managers.functor import ActionTerm

SHAPE = r"expected shape \(2, 7\)"


def ctrl(env) -> torch.Tensor:
    return env.sim.ctrl[:, env.robot.pos_act[:ARM_ACTIVE]].clone()


@pytest.mark.parametrize(
    "action, error, match",
    [
        (None, TypeError, "NoneType"),
        ("0.1", TypeError, "str"),
        (torch.zeros(2, 7, dtype=torch.bool), TypeError, "torch.bool"),
        (np.zeros((2, 7), dtype=np.complex64), TypeError, "complex64"),
        ([[0.0] * 7, [0.0] * 6], TypeError, "numeric array"),
        ({"not": "numbers"}, ValueError, "expected some of"),
        (torch.zeros(3, 7), ValueError, SHAPE),
        (torch.zeros(2, 5), ValueError, SHAPE),
        (torch.zeros(7, 2), ValueError, SHAPE),
        (torch.zeros(2, 7, 1), ValueError, SHAPE),
        (0.5, ValueError, SHAPE),
        (torch.zeros(2, 7, device="meta"), ValueError, "device meta"),
        (torch.full((2, 7), float("nan")), ValueError, r"NaN or infinite values in env\(s\) \[0, 1\]"),
        (np.array([[0.0] * 7, [0.0] * 6 + [np.inf]]), ValueError, r"env\(s\) \[1\]"),
    ],
)
def test_bad_actions_get_one_clear_error(make_env, action, error, match) -> None:
    env = make_env()
    env.reset()
    with pytest.raises(error, match=match) as err:
        env.step(action)
    if error is ValueError and "shape" in match:
        assert "action space Box(shape=(2, 7), dtype=float32)" in str(err.value)


def test_numpy_lists_ints_and_1d_actions_follow_the_rule(make_env) -> None:
    env = make_env()
    env.reset()
    target = np.linspace(-0.3, 0.3, ARM_ACTIVE)
    env.step(np.stack([target, target]))  # float64 numpy: converted
    assert torch.allclose(ctrl(env), torch.from_numpy(np.stack([target, target])).float().double())
    env.step(target.tolist())  # 1-D list of action_dim values: the same action for every env
    assert torch.allclose(ctrl(env)[1], torch.from_numpy(target).float().double())
    env.step([[0] * ARM_ACTIVE, [1] * ARM_ACTIVE])  # ints are converted
    assert ctrl(env)[1].tolist() == [1.0] * ARM_ACTIVE
    env.step(torch.zeros(2, ARM_DOF))  # full-dof commands stay accepted without action terms
    assert ctrl(env).abs().max() == 0


def test_dict_commands_without_terms_are_checked_per_key(make_env) -> None:
    env = make_env()
    env.reset()
    env.step({"qpos": torch.full((2, ARM_ACTIVE), 0.1)})
    assert torch.allclose(ctrl(env), torch.full((2, ARM_ACTIVE), 0.1, dtype=torch.float64))
    with pytest.raises(ValueError, match=r"keys \['qpose'\].*expected some of \['qpos', 'qvel', 'qf'\]"):
        env.step({"qpose": torch.zeros(2, ARM_ACTIVE)})
    with pytest.raises(ValueError, match=r"action\['qf'\] has shape \(2, 3\)"):
        env.step({"qf": torch.zeros(2, 3)})


class Gripper(ActionTerm):
    """A 1-D term (open/close) driving the first joint."""

    input_key = "qpos"

    @property
    def action_dim(self) -> int:
        return 1

    def process_action(self, action: torch.Tensor) -> torch.Tensor:
        out = torch.zeros(action.shape[0], ARM_ACTIVE)
        out[:, 0] = action[:, 0]
        return out


def test_terms_take_their_width_scalars_only_for_one_dim_spaces(make_env) -> None:
    env = make_env(actions={"grip": ActionTermCfg(func=Gripper)})
    env.reset()
    assert env.action_space.shape == (2, 1)
    env.step(0.2)  # a scalar for a one-value action space: every env
    assert ctrl(env)[:, 0].tolist() == pytest.approx([0.2, 0.2])
    env.step(torch.tensor([0.1, -0.1]))  # one value per env
    assert ctrl(env)[:, 0].tolist() == pytest.approx([0.1, -0.1])
    env.step({"grip": [[0.3], [0.3]]})  # a dict by term name
    assert ctrl(env)[:, 0].tolist() == pytest.approx([0.3, 0.3])
    with pytest.raises(ValueError, match=r"expected shape \(2, 1\).*action terms \['grip'\] take \[1\]"):
        env.step(torch.zeros(2, 2))


def test_the_common_case_is_passed_through_untouched() -> None:
    check = ActionChecker(2, [3], torch.device("cpu"), None)
    action = torch.zeros(2, 3)
    assert check(action) is action
    assert check(torch.zeros(3, dtype=torch.float64)).dtype == torch.float32


def test_host_array_is_the_view_of_the_last_action_passed_as_it_was() -> None:
    check = ActionChecker(2, [7], torch.device("cpu"), None)
    action = torch.rand(2, 7)
    assert check(action) is action
    view = check.host_array(action)
    assert view is not None
    assert np.shares_memory(view, action.numpy())
    assert check.host_array(action.clone()) is None  # another tensor: no view
    converted = check(action.double())  # converted: a new tensor, and no view of anything
    assert check.host_array(converted) is None
    assert check.host_array(action) is None
    with pytest.raises(ValueError, match="NaN"):
        check(torch.full((2, 7), float("nan")))
    assert check.host_array(action) is None


def test_a_sparse_tensor_action_gets_a_clear_error(make_env) -> None:
    env = make_env()
    env.reset()
    sparse = torch.zeros(2, ARM_ACTIVE).to_sparse()
    with pytest.raises(TypeError, match=r"action is a torch.sparse_coo tensor; expected .* dense tensor .*to_dense"):
        env.step(sparse)


def _box(low: list, high: list):
    import gymnasium as gym

    return gym.spaces.Box(low=np.array([low] * 2, np.float32), high=np.array([high] * 2, np.float32))


def test_out_of_space_values_are_counted_per_env_step() -> None:
    check = ActionChecker(2, [3], torch.device("cpu"), _box([-1, -1, -1], [1, 1, 1]))
    check(torch.zeros(2, 3))
    assert check.out_of_space == 0
    check(torch.tensor([[0.0, 5.0, 0.0], [0.0, 0.0, 0.0]]))
    assert check.out_of_space == 1
    check(np.full((2, 3), -2.0))  # the converted path counts too
    assert check.out_of_space == 3
    per_joint = ActionChecker(2, [3], torch.device("cpu"), _box([-1, -2, 0], [1, 2, 3]))
    per_joint(torch.tensor([[0.5, -1.5, 2.5], [0.5, 1.5, -0.1]]))  # only env 1's last value is outside
    assert per_joint.out_of_space == 1


def test_strict_raises_naming_the_env_value_and_bounds() -> None:
    check = ActionChecker(2, [3], torch.device("cpu"), _box([-1, -2, 0], [1, 2, 3]), strict=True)
    check(torch.tensor([[1.0, -2.0, 3.0], [-1.0, 2.0, 0.0]]))  # the bounds are inside
    with pytest.raises(ValueError, match=r"env\(s\) \[1\]: value 1e\+30 at index 1 is not in \[-2, 2\]"):
        check(torch.tensor([[0.0, 0.0, 0.0], [0.0, 1e30, 0.0]]))
    assert check.out_of_space == 0
