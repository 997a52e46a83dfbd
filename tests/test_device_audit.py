"""Host waits per env step on the ``warp`` backend, counted on Warp's CPU device by the device
audit (:class:`~embodichain_core.sim.backend.device_audit.HostWaitAudit`).

On a GPU every device-to-host read and every blocking host-to-device copy in the step stalls
the stream. PushCube-v1 (joint-delta actions, reward terms, a TCP observation) steps with at
most 2 of them per step: the done/divergence flags are the one read. The first tests show the
audit counts the kinds of wait it claims to, so the budget test cannot pass by counting nothing.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Iterator

import pytest
import torch

from core_testlib import audited_push_cube

from embodichain_core.sim.backend.device_audit import HostWaitAudit

#: The most host waits an env step of PushCube-v1 may make on the device route.
WAIT_BUDGET = 2
STEPS = 6


@pytest.fixture(scope="module")
def audited() -> Iterator[tuple[Any, HostWaitAudit]]:
    """PushCube-v1 on backend warp (Warp's CPU device, 2 envs), built and reset inside the
    audit so that the tensors it makes on its device are known (and it takes the device
    code paths: the audit builds it without host arrays)."""
    yield from audited_push_cube()


def _count(audit: HostWaitAudit, fn: Any) -> dict[str, float]:
    audit.clear()
    fn()
    return audit.per_step(1)["by_kind"]


def test_the_audit_counts_reads_and_host_copies(audited: tuple) -> None:
    env, audit = audited
    sim = env.sim
    assert _count(audit, lambda: float(sim.qpos[0, 0])) == {"float": 1.0}
    assert _count(audit, lambda: bool(sim.qvel.abs().max() > 1.0)) == {"bool": 1.0}
    assert _count(audit, lambda: sim.qpos[:, [0, 1]]) == {"host_index": 1.0}  # the index list is copied over
    assert _count(audit, lambda: torch.ones(3).to(env.device)) == {"to_device": 1.0}
    assert _count(audit, lambda: torch.nonzero(sim.qpos[:, 0] > 0)) == {"nonzero": 1.0}
    on_device = torch.zeros(2, device=env.device)
    assert _count(audit, lambda: (on_device + sim.qpos[:, 0]) * 2.0) == {}  # device ops wait for nothing
    assert _count(audit, lambda: torch.zeros(2)[torch.tensor([1])]) == {}  # host ops neither


def _mixed(audit: HostWaitAudit, fn: Any) -> int:
    audit.clear()
    fn()
    return sum(m["count"] for m in audit.per_step(1)["mixed"])


def test_the_audit_lists_ops_that_would_mix_devices_on_cuda(audited: tuple) -> None:
    env, audit = audited
    qpos = env.sim.qpos[:, :2]
    host = torch.ones(2, 2)
    assert _mixed(audit, lambda: qpos + host) == 1  # CUDA: expected all tensors on the same device
    assert _mixed(audit, lambda: torch.stack((qpos, host))) == 1
    assert _mixed(audit, lambda: host.clone().__setitem__((slice(None), [0]), qpos[:, :1])) == 1
    assert _mixed(audit, lambda: qpos * torch.tensor(2.0)) == 0  # a host scalar is allowed
    assert _mixed(audit, lambda: qpos.clone().copy_(host)) == 0  # an explicit copy is a wait, not an error
    assert _mixed(audit, lambda: qpos + host.to(env.device)) == 0
    # a factory naming a host tensor's device on the CPU may stand for either side
    eye = torch.eye(2, device=host.device)
    assert _mixed(audit, lambda: (host @ eye, qpos @ eye)) == 0
    assert audit.per_step(1)["per_step"] == 0  # listed apart from the waits


def test_the_audit_refuses_an_env_on_host_views(audited: tuple) -> None:
    env, _ = audited
    HostWaitAudit.check_env(env)  # the device route: accepted
    device_route = env.sim.capabilities
    env.sim.capabilities = dataclasses.replace(device_route, host_arrays=True)
    try:
        with pytest.raises(ValueError, match="inside the audit's with-block"):
            HostWaitAudit.check_env(env)
    finally:
        env.sim.capabilities = device_route


def test_an_env_step_waits_for_the_device_at_most_twice(audited: tuple) -> None:
    env, audit = audited
    action = torch.full(env.action_space.shape, 0.5, device=env.device)
    env.step(action)  # first-step work (lazy caches) stays out of the count
    audit.clear()
    for _ in range(STEPS):
        env.step(action)
    report = audit.per_step(STEPS)
    sites = "\n".join(f"{s['per_step']:.2f} {s['kind']}: {s['site']}" for s in report["sites"])
    assert report["per_step"] <= WAIT_BUDGET, f"{report['per_step']} host waits per step:\n{sites}"
    assert not report["mixed"], f"ops that raise on CUDA: {report['mixed']}"
    assert report["per_step"] >= 1, "the done flags are read every step: the audit counted nothing"
    assert env.sim.qpos.abs().sum() > 0
