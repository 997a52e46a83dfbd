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


def test_one_check_finds_nan_inf_and_out_of_space_values_in_every_form() -> None:
    unbounded = ActionChecker(2, [3], torch.device("cpu"), None)
    for bad in (float("nan"), float("inf"), float("-inf")):
        action = torch.zeros(2, 3)
        action[1, 2] = bad
        with pytest.raises(ValueError, match=r"NaN or infinite values in env\(s\) \[1\]"):
            unbounded(action)  # passed through as it is: checked all the same
        with pytest.raises(ValueError, match=r"NaN or infinite values in env\(s\) \[1\]"):
            unbounded(action.double())  # converted
    assert unbounded(torch.full((2, 3), 1e30, requires_grad=True)).requires_grad  # finite: fine, untouched
    bounded = ActionChecker(2, [3, 5], torch.device("cpu"), _box([-1, -1, -1], [1, 1, 1]), {"qf": [3]})
    with pytest.raises(ValueError, match=r"NaN or infinite values in env\(s\) \[0\]"):
        bounded(torch.tensor([[float("inf"), 0.0, 0.0], [0.0, 0.0, 0.0]]))
    bounded(torch.full((2, 5), 9.0))  # another width: the space's bounds do not apply
    bounded({"qf": torch.full((2, 3), 9.0)})  # nor to a dict's values
    assert bounded.out_of_space == 0
    bounded(torch.full((2, 3), 9.0))
    assert bounded.out_of_space == 2


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
