"""The ``warp`` backend (MuJoCo Warp, here on Warp's CPU device): it passes the simulation
interface's conformance checks, the demo scene steps as on ``mujoco_batch`` within float32
tolerance, subset resets touch only their envs, per-env model writes give per-env physics,
and a per-env write it cannot do is a ConfigError at build.

Warp compiles MuJoCo Warp's kernels once into ``.warp_cache/`` (about 30-50 s cold; later
runs load them in milliseconds); the env pairs are module fixtures.
"""

from __future__ import annotations

from typing import Any, Iterator

import mujoco
import numpy as np
import pytest
import torch

from core_testlib import base_cfg

from embodichain_core.config.errors import ConfigError
from embodichain_core.config.validate import check_sim
from embodichain_core.demo import DemoSceneEnv, demo_cfg
from embodichain_core.sim.backend import SimBackend, conformance
from embodichain_core.sim.backend.warp_device import cpu_device_route
from embodichain_core.sim.backend.warp_sim import WarpSim
from embodichain_core.sim.cfg import SimulationManagerCfg
from embodichain_core.sim.scene import Scene

NUM_ENVS = 8
STEPS = 50
#: The demo arm's joints straight up (its configured pose reaches into the table, where
#: MuJoCo Warp's box-box contacts differ from MuJoCo's; see docs/backends.md).
CLEAR_QPOS = [0.0] * 7 + [0.02, 0.02]


def make_warp_sim(model: mujoco.MjModel, num_envs: int) -> WarpSim:
    return WarpSim(model, num_envs, substeps=2)


@pytest.mark.parametrize("check", conformance.CHECKS, ids=lambda c: c.__name__)
def test_warp_sim_conforms(check: Any) -> None:
    check(make_warp_sim)


def test_views_are_the_warp_arrays() -> None:
    sim = make_warp_sim(mujoco.MjModel.from_xml_string(conformance.SCENE), 2)
    assert isinstance(sim, SimBackend)
    assert sim.dtype == torch.float32
    assert not sim.capabilities.float64
    assert not sim.capabilities.subset_step
    assert sim.qpos.data_ptr() == sim.wp_data.qpos.ptr  # zero-copy: the torch view is Warp's memory
    sim.arrays["qpos"][1, 0] = 0.25  # the numpy view on the CPU device is the same memory too
    assert float(sim.qpos[1, 0]) == 0.25
    assert sim.xmat.shape == (2, sim.model.nbody, 9)  # mujoco.batch's layout, still a view


def test_a_saved_state_row_is_refused_and_changes_nothing() -> None:
    sim = make_warp_sim(mujoco.MjModel.from_xml_string(conformance.SCENE), 2)
    assert not sim.restores_state_rows  # the scene keeps its default-row fast path off here
    sim.step(3)
    before = sim.qpos.clone()
    with pytest.raises(ValueError, match="does not restore saved state rows"):
        sim.reset([0], state=np.zeros(10))
    assert torch.equal(sim.qpos, before)
    sim.reset([0], state=None)
    assert np.allclose(sim.qpos[0].numpy(), sim.model.qpos0)


def test_a_step_runs_the_constants_that_model_writes_made_due() -> None:
    """``set_const`` runs before the next step (not only before a host copy), once, for the writes."""
    sim = make_warp_sim(mujoco.MjModel.from_xml_string(conformance.SCENE), 2)
    box = sim.model.body("box").id
    shared = sim.model.body_subtreemass[box]
    sim.set_model_field("body_mass", [1], box, 2.5)
    assert np.allclose(sim.model_field("body_subtreemass")[:, box], [shared, shared])  # deferred
    sim.step(1)
    subtree = sim.model_field("body_subtreemass")[:, box]
    assert np.allclose(subtree, [shared, 2.5]), subtree


def test_a_failed_graph_capture_falls_back_to_direct_launches(monkeypatch: Any) -> None:
    sim = make_warp_sim(mujoco.MjModel.from_xml_string(conformance.SCENE), 2)
    assert sim.graphs.enabled  # Warp records launches on its CPU device too

    class NoCapture:
        def __init__(self, *args: Any, **kwargs: Any):
            pass

        def __enter__(self) -> None:
            raise RuntimeError("capture is not possible here")

        def __exit__(self, *exc: Any) -> bool:
            return False

    monkeypatch.setattr(sim.wp, "ScopedCapture", NoCapture)
    sim.graphs.clear()
    before = sim.qpos.clone()
    with pytest.warns(RuntimeWarning, match="graph capture failed"):
        assert sim.step(1) == []
    assert not sim.graphs.enabled
    assert not torch.equal(sim.qpos, before), "the fallback did not step"


@pytest.mark.parametrize(
    "name, why", [("geom_contype", "colliding geom pairs"), ("opt.solver", "one value"), ("mesh_vert", "mesh geometry")]
)
def test_unsupported_per_env_fields_name_field_and_backend(name: str, why: str) -> None:
    sim = make_warp_sim(mujoco.MjModel.from_xml_string(conformance.SCENE), 2)
    with pytest.raises(ConfigError, match=rf"model field '{name}' cannot take per-env values on backend 'warp'.*{why}"):
        sim.declare_per_env([name])
    with pytest.raises(ConfigError, match="Did you mean 'body_mass'"):
        sim.set_model_field("body_mas", [0], 1, 2.0)


def test_the_kernel_cache_is_the_project_folder_unless_named(monkeypatch: Any, tmp_path: Any) -> None:
    from pathlib import Path

    from embodichain_core.sim.backend.warp_device import CACHE_ENV, default_cache_dir

    monkeypatch.delenv(CACHE_ENV, raising=False)
    root = Path(__file__).resolve().parents[1]
    assert default_cache_dir() == root / ".warp_cache"
    assert "/.warp_cache/" in (root / ".gitignore").read_text().splitlines()
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    assert default_cache_dir() == tmp_path


def test_without_mujoco_warp_the_error_says_how_to_install_it(monkeypatch: Any) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "mujoco_warp", None)  # as if it were not installed
    with pytest.raises(ConfigError, match=r"sim_cfg.backend: backend 'warp' needs MuJoCo Warp: pip install"):
        make_warp_sim(mujoco.MjModel.from_xml_string(conformance.SCENE), 2)


@pytest.mark.parametrize(
    "changes, path, message",
    [
        ({"backend": "wrap"}, "sim_cfg.backend", "Did you mean 'warp'"),
        ({"backend": "warp", "sim_device": "gpu"}, "sim_cfg.sim_device", "'cpu', 'cuda' or 'cuda:N'"),
        ({"backend": "warp", "solver": "PGS"}, "sim_cfg.physics_config.solver", "'Newton' or 'CG'"),
        ({"backend": "warp", "sim_device": "cuda:64"}, "sim_cfg.sim_device", "'cuda:64': this machine has"),
    ],
)
def test_backend_settings_are_validated(changes: dict, path: str, message: str) -> None:
    sim = SimulationManagerCfg()
    sim.physics_config.solver = changes.pop("solver", sim.physics_config.solver)
    for key, value in changes.items():
        setattr(sim, key, value)
    with pytest.raises(ConfigError, match=message) as err:
        check_sim(sim, "sim_cfg")
    assert err.value.path == path


def test_cuda_without_a_gpu_is_one_error_before_the_build(monkeypatch: Any, capsys: Any) -> None:
    """``--device cuda`` on a machine without a GPU: the run stops at the config check,
    naming the key and the device that works, before the scene is built."""
    from embodichain_core.cli import run_env
    from embodichain_core.demo import DEMO_CONFIG

    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(Scene, "build", lambda *a, **k: pytest.fail("the scene was built"))
    sim = SimulationManagerCfg(backend="warp", sim_device="cuda")
    with pytest.raises(ConfigError, match=r"'cuda': this machine has no CUDA GPU; use 'cpu'") as err:
        check_sim(sim, "sim_cfg")
    assert err.value.path == "sim_cfg.sim_device"
    code = run_env.main(["--gym_config", str(DEMO_CONFIG), "--backend", "warp", "--device", "cuda", "--headless"])
    out = capsys.readouterr()
    assert code != 0
    assert "sim_cfg.sim_device: 'cuda': this machine has no CUDA GPU; use 'cpu'" in out.out + out.err


def test_backend_is_set_from_configs_and_the_command_line(tmp_path: Any) -> None:
    from embodichain_core.cli import run_env
    from embodichain_core.config.loader import load_config_file, load_gym_config
    from embodichain_core.demo import DEMO_CONFIG

    data = load_config_file(DEMO_CONFIG)
    assert load_gym_config({**data, "backend": "warp"})[1].sim_cfg.backend == "warp"  # flat key
    path = tmp_path / "demo.yaml"
    path.write_text("id: Demo-v0\nrobot: {uid: arm, fpath: arm7.xml}\nenv: {}\nsim_cfg: {backend: warp}\n")
    assert load_gym_config(path)[1].sim_cfg.backend == "warp"
    assert load_gym_config(data)[1].sim_cfg.backend == "mujoco_batch"  # the default
    args = run_env.build_parser().parse_args(["--backend", "warp", "--device", "cpu"])
    overrides = run_env.overrides_from_args(args)
    assert overrides == {"backend": "warp", "device": "cpu"}
    assert load_gym_config(data, overrides)[1].sim_cfg.backend == "warp"
    with pytest.raises(SystemExit):
        run_env.build_parser().parse_args(["--backend", "gpu"])


# -- the demo scene on both backends -------------------------------------------------------------
def _demo(backend: str) -> DemoSceneEnv:
    cfg = demo_cfg()
    cfg.num_envs = cfg.sim_cfg.num_envs = NUM_ENVS
    cfg.sim_cfg.backend = backend
    cfg.verbose = False
    cfg.robot.init_qpos = list(CLEAR_QPOS)
    return DemoSceneEnv(cfg)


@pytest.fixture(scope="module")
def demo_pair() -> Iterator[tuple[DemoSceneEnv, DemoSceneEnv]]:
    cpu, warp = _demo("mujoco_batch"), _demo("warp")
    yield cpu, warp
    cpu.close()
    warp.close()


def test_demo_scene_steps_as_on_mujoco_batch(demo_pair: tuple) -> None:
    cpu, warp = demo_pair
    assert isinstance(warp.sim, WarpSim)
    assert warp.sim.qpos.dtype == torch.float32
    cpu.reset(seed=0)
    warp.reset(seed=0)
    rng = torch.Generator().manual_seed(0)
    for _ in range(STEPS):
        action = torch.rand(cpu.action_space.shape, generator=rng) * 0.4 - 0.2
        obs_cpu, *_ = cpu.step(action)
        obs_warp, *_ = warp.step(action)
        for key in ("qpos", "qvel"):
            assert torch.allclose(obs_warp["robot"][key].double(), obs_cpu["robot"][key].double(), atol=1e-4), key
    moved = (cpu.sim.qpos - torch.as_tensor(cpu.scene.model.qpos0)).abs().max()
    assert moved > 0.05, "the actions did not move the arm: the comparison is void"
    assert torch.allclose(warp.sim.qpos.double(), cpu.sim.qpos, atol=1e-5)
    assert torch.allclose(warp.sim.xpos.double(), cpu.sim.xpos, atol=1e-5)  # derived views current after step


@pytest.fixture(scope="module")
def device_demo() -> Iterator[DemoSceneEnv]:
    """The demo scene on Warp's CPU device built on the route a GPU takes (no host arrays)."""
    with cpu_device_route():
        env = _demo("warp")
    yield env
    env.close()


def test_device_route_gives_the_same_steps(demo_pair: tuple, device_demo: DemoSceneEnv) -> None:
    """Without host arrays (what CUDA gets), entities and the robot commands take their device
    code paths; the steps agree all the same (checked on Warp's CPU device)."""
    cpu, env = demo_pair[0], device_demo
    assert not env.sim.capabilities.host_arrays
    assert not hasattr(env.sim, "arrays")  # no numpy stand-in for device memory
    assert not env._robot_io.host
    cpu.reset(seed=0)
    env.reset(seed=0)
    rng = torch.Generator().manual_seed(2)
    for _ in range(20):
        action = torch.rand(cpu.action_space.shape, generator=rng) * 0.4 - 0.2
        cpu.step(action)
        env.step(action)
    assert torch.allclose(env.sim.qpos.double(), cpu.sim.qpos, atol=1e-5)


def _entity_io(env: DemoSceneEnv) -> dict[str, torch.Tensor]:
    """Writes joint positions, velocities and root poses through the entities of ``env``,
    then reads them back (and what follows from them) through the same entities."""
    gen = torch.Generator().manual_seed(5)
    robot, cube, table = env.robot, env.scene["cube_red"], env.scene["table"]
    env.reset(seed=0)
    qpos = torch.as_tensor(CLEAR_QPOS, dtype=torch.float64) + 0.3 * torch.rand(NUM_ENVS, robot.dof, generator=gen)
    robot.set_qpos(qpos, target=False)
    robot.set_qpos(qpos[[1, 3], :2] + 0.1, joint_ids=[0, 1], env_ids=[1, 3])  # drive targets only
    robot.set_qvel(torch.rand(2, robot.dof, generator=gen, dtype=torch.float64), env_ids=[0, 2], target=False)
    pose = np.tile([0.5, 0.1, 0.6, 0.8, 0.0, 0.6, 0.0], (NUM_ENVS, 1)) + np.arange(NUM_ENVS)[:, None] * 0.01
    cube.set_local_pose(pose)
    cube.set_velocity(torch.tensor([[0.1, 0.0, 0.0, 0.0, 0.0, 2.0]]).expand(NUM_ENVS, 6))
    table.set_local_pose(torch.tensor([[0.6, 0.05, 0.2, 1.0, 0.0, 0.0, 0.0]]).expand(2, 7), env_ids=[4, 5])
    link = robot.link_names[-1]
    return {
        "qpos": robot.get_qpos(),
        "targets": robot.get_qpos(target=True),
        "qpos_array": torch.as_tensor(robot.qpos_array([2, 6], [0, 3])),
        "qvel": robot.get_qvel(),
        "root": robot.get_local_pose(),
        "link": robot.get_link_pose(link),
        "link_of_some": robot.get_link_pose(link, env_ids=[1, 3]),
        "cube": cube.get_local_pose(),
        "cube_velocity": cube.get_velocity(),
        "table": table.get_local_pose(),
    }


def test_entities_read_and_write_alike_on_both_routes(demo_pair: tuple, device_demo: DemoSceneEnv) -> None:
    """Every entity holds the route chosen at build: on the device route the sim has no host
    arrays, so an entity that still chose numpy per call fails here; joint positions and root
    poses written and read back through either route are the same values."""
    from embodichain_core.sim.backend.state_route import DeviceRoute, HostRoute
    from embodichain_core.sim.entities.base import Entity

    host, device = demo_pair[1], device_demo
    for env, route in ((host, HostRoute), (device, DeviceRoute)):
        entities = [e for e in env.scene.entities.values() if isinstance(e, Entity)]
        assert len(entities) >= 5
        assert all(type(e.state_route) is route for e in entities), env.sim.capabilities
    want, got = _entity_io(host), _entity_io(device)
    for key, value in want.items():
        assert (got[key].dtype, got[key].device) == (value.dtype, value.device), key
        assert torch.equal(got[key], value), key
    qpos = torch.as_tensor(CLEAR_QPOS, dtype=torch.float64) + 0.3 * torch.rand(
        NUM_ENVS, host.robot.dof, generator=torch.Generator().manual_seed(5)
    )
    driven = ~torch.isin(torch.arange(host.robot.dof), torch.as_tensor(host.robot.mimic_ids, dtype=torch.long))
    assert torch.allclose(want["qpos"][:, driven].double(), qpos[:, driven], atol=1e-6)  # the writes happened
    assert torch.allclose(want["cube"][:, 0].double(), torch.as_tensor(np.arange(NUM_ENVS) * 0.01 + 0.5), atol=1e-6)
    assert torch.allclose(want["table"][[4, 5], 1], torch.tensor([0.05, 0.05]))


def test_subset_reset_resets_only_those_envs(demo_pair: tuple) -> None:
    _, env = demo_pair
    env.reset(seed=0)
    start = env.sim.qpos.clone()
    for _ in range(5):
        env.step(torch.full(env.action_space.shape, 0.3))
    stepped = env.sim.qpos.clone()
    env.reset(options={"reset_ids": [1, 5]})
    now = env.sim.qpos
    others = [i for i in range(NUM_ENVS) if i not in (1, 5)]
    assert torch.equal(now[others], stepped[others]), "a subset reset changed other envs"
    assert torch.allclose(now[[1, 5]], start[[1, 5]], atol=1e-6), "the reset envs did not go back"
    assert not torch.allclose(stepped[[1, 5]], start[[1, 5]], atol=1e-3)


# -- per-env model fields --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def warp_env() -> Iterator[Any]:
    from embodichain_core.envs import EmbodiedEnv

    cfg = base_cfg(num_envs=4)
    cfg.sim_cfg.backend = "warp"
    env = EmbodiedEnv(cfg)
    yield env
    env.close()


def test_mass_friction_damping_take_per_env_values(warp_env: Any) -> None:
    env, sim = warp_env, warp_env.sim
    cube, arm = env.scene["cube"], env.scene["arm"]
    cube.set_mass([0.5, 1.0, 2.0, 4.0])
    cube.set_friction([0.2, 0.4, 0.6, 0.8])
    dof = int(arm.dof_adr[0])
    sim.set_model_field("dof_damping", [1, 3], dof, np.array([3.0, 7.0]))
    assert torch.allclose(cube.get_mass().double(), torch.tensor([0.5, 1.0, 2.0, 4.0], dtype=torch.float64))
    assert torch.allclose(cube.get_friction().double(), torch.tensor([0.2, 0.4, 0.6, 0.8], dtype=torch.float64))
    assert np.allclose(
        sim.model_field("dof_damping")[:, dof], [arm_damping := env.scene.model.dof_damping[dof], 3.0, arm_damping, 7.0]
    )
    env.step(torch.zeros(env.action_space.shape))  # the constants are recomputed once, before the step
    for i, mass in enumerate([0.5, 1.0, 2.0, 4.0]):
        host = sim.get_model(i)  # what MuJoCo Warp simulates in world i (as a host MjModel)
        assert np.isclose(host.body_mass[cube.body_id], mass, rtol=1e-6)
        assert np.isclose(host.body_subtreemass[cube.body_id], mass, rtol=1e-6), "set_const did not run"
    # physics reads the per-world values: damping slows the first joint of envs 1 and 3
    arm.set_qvel(torch.full((4, 1), 2.0), joint_ids=[0], target=False)
    arm.set_qpos(arm.get_qpos()[:, :1], joint_ids=[0])
    for _ in range(3):
        sim.step(1)
    speed = sim.qvel[:, dof].abs()
    assert speed[1] < speed[0], speed
    assert speed[3] < speed[1], speed
    assert speed[3] < speed[2], speed


def test_subset_step_of_a_functor_and_divergence_through_the_env_loop() -> None:
    """A settling functor's subset step runs through the fallback, and a diverged env is
    truncated and reset by the env loop, as on mujoco_batch."""
    from core_testlib import zero_action
    from embodichain_functors._sim import step_envs

    from embodichain_core.envs import EmbodiedEnv

    cfg = base_cfg(num_envs=3)
    cfg.sim_cfg.backend = "warp"
    env = EmbodiedEnv(cfg)
    try:
        env.reset(seed=0)
        cube = env.scene["cube"]
        untouched = env.sim.qpos[2].clone()
        env.sim.qvel[1, cube.dof_adr] = float("nan")
        env.sim.mark_dirty([1])
        assert step_envs(env, torch.tensor([0, 1]), 2) == [1]
        assert torch.equal(env.sim.qpos[2], untouched), "the subset step moved an env outside it"
        with pytest.warns(RuntimeWarning, match=r"diverged in env\(s\) \[1\]"):
            _, _, _, truncated, info = env.step(zero_action(env))
        assert info["diverged"].tolist() == [False, True, False]
        assert truncated.tolist() == [False, True, False]
        assert torch.isfinite(env.sim.qpos).all()  # the autoreset cleared it
    finally:
        env.close()
