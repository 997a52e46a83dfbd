"""The settings of a part's IK solver (``solver_cfg[part]`` of a robot config), read by
:class:`~embodichain_robots.kinematics.solver.DLSSolver` and
:class:`~embodichain_robots.kinematics.mj_solver.MjDLSSolver`.

Example:
    >>> IKSolverCfg(root_link_name="base", end_link_name="hand", num_restarts=2).max_iterations
    20
"""

from __future__ import annotations

from typing import List, Optional

from embodichain_core.utils.configclass import configclass

__all__ = ["IKSolverCfg"]


@configclass
class IKSolverCfg:
    """Settings of one part's solver (``solver_cfg[part]`` of a robot config).

    Attributes:
        class_type: ``"DLSSolver"`` (batched torch chain, default) or
            ``"MjDLSSolver"`` (MuJoCo Jacobians per env; slower, for reference).
        root_link_name: the link the targets are expressed in.
        end_link_name: the flange link; the TCP is ``end_link @ tcp``.
        tcp: 4x4 TCP in the end link frame.
        joint_names: chain joints; None takes the joints on the path.
        max_iterations: DLS iterations per attempt.
        num_restarts: rounds of random restarts for envs that did not converge.
        num_samples: random seeds per unsolved env and round (solved together).
        pool_factor: each round's seeds are the ``num_samples`` best (by TCP pose
            error) of ``pool_factor * num_samples`` random joint samples.
        rot_weight: metres per radian when ranking pose errors.
        pos_tol: success threshold on the position error (m).
        rot_tol: success threshold on the rotation error (rad).
        damping: the DLS damping ``lambda``.
        max_step: largest joint step per iteration (rad or m).
        seed: seed of the restart sampler.
    """

    class_type: str = "DLSSolver"
    root_link_name: str = ""
    end_link_name: str = ""
    tcp: List[List[float]] = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]
    joint_names: Optional[List[str]] = None
    max_iterations: int = 20
    num_restarts: int = 4
    num_samples: int = 8
    pool_factor: int = 4
    rot_weight: float = 0.2
    pos_tol: float = 1e-4
    rot_tol: float = 1e-3
    damping: float = 1e-3
    max_step: float = 1.0
    seed: int = 0
