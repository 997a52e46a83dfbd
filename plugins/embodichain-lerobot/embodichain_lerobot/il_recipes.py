"""The imitation pipeline's two recipes: what the policy reads, and how ACT is trained on it.

* ``state``: ``observation.state`` (the joints) and ``observation.environment_state`` (the
  object poses the recorder's ``environment_state`` lists). No camera is rendered.
* ``camera``: ``observation.state`` and the images of the cameras named by ``cameras``
  (``observation.images.<uid>``); no object pose. The other cameras of the config are
  dropped, so only what the policy reads is rendered.

Both train lerobot's ACT, on the CPU by default: one forward pass gives a chunk of actions,
the scripted demonstrations are unimodal (no VAE), and the model is small (256-wide
transformer, 2 encoder layers, 1 decoder layer). The camera recipe trains its ResNet-18 from
scratch (nothing is downloaded), at the transformer's learning rate (lerobot's default
backbone rate, 1e-5, suits ImageNet weights being fine-tuned, not a backbone learning from
nothing), with colour jitter and small random shifts of the images (the augmentation that
matters most for small image datasets). At inference both plan a chunk every step and
average the overlapping predictions (ACT's temporal ensembling): on PickFork-v1 the same
camera checkpoint succeeded in 0.58 of 50 validation episodes with it, 0.34 executing 10
actions of each chunk open loop (docs/learning.md, section 12).

Example:
    >>> config = pipeline_config(Path("pick_fork_camera.json"), "camera", ["policy_cam"])  # doctest: +SKIP
    >>> flags = train_flags("camera")                                                     # doctest: +SKIP
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Sequence

__all__ = [
    "POLICIES",
    "LR_SCHEDULES",
    "ACT_FLAGS",
    "CAMERA_FLAGS",
    "pipeline_config",
    "train_flags",
    "schedule_flags",
    "camera_uids",
]

#: The recipes ``--policy`` accepts.
POLICIES = ("state", "camera")
#: The learning-rate schedules ``--lr_schedule`` accepts: lerobot's ACT preset (a constant rate),
#: or the same AdamW with the rate decayed on a cosine to 1% of it by the last step.
LR_SCHEDULES = ("constant", "cosine")

#: Actions per predicted chunk (``--chunk_size``): 0.8 s at the IL tasks' 25 Hz.
CHUNK_SIZE = 20


#: ACT settings shared by both recipes (lerobot-train flags). ``n_action_steps=1`` with
#: ``temporal_ensemble_coeff``: a chunk is planned every step and the overlapping predictions
#: of the same step are averaged, the older ones weighted by ``exp(-0.01 * age)``; both are
#: inference settings (they do not enter the loss).
ACT_FLAGS = (
    "--policy.type=act",
    f"--policy.chunk_size={CHUNK_SIZE}",
    "--policy.n_action_steps=1",
    "--policy.temporal_ensemble_coeff=0.01",
    "--policy.dim_model=256",
    "--policy.dim_feedforward=1024",
    "--policy.n_encoder_layers=2",
    "--policy.n_decoder_layers=1",
    "--policy.use_vae=false",
    "--policy.optimizer_lr=1e-4",
    "--policy.push_to_hub=false",
)

#: Image augmentation of the camera recipe: at most 3 of these per frame (lerobot's
#: ``ImageTransforms``); ``shift`` moves the image by up to 4% of its size, no rotation.
IMAGE_TRANSFORMS = {
    "brightness": {"weight": 1.0, "type": "ColorJitter", "kwargs": {"brightness": [0.8, 1.2]}},
    "contrast": {"weight": 1.0, "type": "ColorJitter", "kwargs": {"contrast": [0.8, 1.2]}},
    "saturation": {"weight": 1.0, "type": "ColorJitter", "kwargs": {"saturation": [0.5, 1.5]}},
    "hue": {"weight": 1.0, "type": "ColorJitter", "kwargs": {"hue": [-0.05, 0.05]}},
    "shift": {"weight": 1.0, "type": "RandomAffine", "kwargs": {"degrees": 0, "translate": [0.04, 0.04]}},
}

#: What the camera recipe adds to :data:`ACT_FLAGS` (replacing a flag of the same name): the
#: image encoder's training settings and the augmentation.
CAMERA_FLAGS = (
    "--policy.pretrained_backbone_weights=null",
    "--policy.optimizer_lr_backbone=1e-4",
    "--dataset.image_transforms.enable=true",
    "--dataset.image_transforms.max_num_transforms=3",
    "--dataset.image_transforms.tfs=" + json.dumps(IMAGE_TRANSFORMS),
)


def schedule_flags(schedule: str, steps: int) -> tuple[str, ...]:
    """lerobot-train flags of a learning-rate schedule over ``steps`` training steps.

    ``cosine`` replaces ACT's preset (AdamW, lr 1e-4, weight decay 1e-4, gradient norm
    clipped at 10, constant rate) by the same optimizer with 200 warm-up steps and a cosine
    decay to 1e-6 at ``steps``: the last checkpoints are then taken at a small rate, where
    a constant rate leaves every checkpoint a sample of a still-moving model. Its optimizer
    has one parameter group (the camera recipe's backbone rate would be lost: state only).

    Raises:
        ValueError: an unknown schedule.
    """
    if schedule not in LR_SCHEDULES:
        raise ValueError(f"lr_schedule: unknown schedule {schedule!r}; choose one of {', '.join(LR_SCHEDULES)}")
    if schedule == "constant":
        return ()
    return (
        "--use_policy_training_preset=false",
        "--optimizer.type=adamw",
        "--optimizer.lr=1e-4",
        "--optimizer.weight_decay=1e-4",
        "--optimizer.grad_clip_norm=10",
        "--scheduler.type=cosine_decay_with_warmup",
        "--scheduler.num_warmup_steps=200",
        f"--scheduler.num_decay_steps={int(steps)}",
        "--scheduler.peak_lr=1e-4",
        "--scheduler.decay_lr=1e-6",
    )


def train_flags(
    policy: str, schedule: str = "constant", steps: int = 0, chunk_size: int = CHUNK_SIZE
) -> tuple[str, ...]:
    """The lerobot-train policy (augmentation, schedule, chunk) flags of a recipe, each flag once.

    Raises:
        ValueError: ``cosine`` with the camera recipe (its backbone has its own rate), an
            unknown schedule, or a ``chunk_size`` below 1.
    """
    if policy == "camera" and schedule != "constant":
        raise ValueError("lr_schedule: the camera recipe trains at a constant rate (its backbone has its own)")
    if int(chunk_size) < 1:
        raise ValueError(f"chunk_size: at least 1 action per chunk, got {chunk_size}")
    act = tuple(
        f if f != f"--policy.chunk_size={CHUNK_SIZE}" else f"--policy.chunk_size={int(chunk_size)}" for f in ACT_FLAGS
    )
    if policy != "camera":
        return act + schedule_flags(schedule, steps)
    replaced = {flag.split("=", 1)[0] for flag in CAMERA_FLAGS}
    return tuple(f for f in act if f.split("=", 1)[0] not in replaced) + CAMERA_FLAGS


def camera_uids(data: dict[str, Any]) -> list[str]:
    """The uids of the config's camera sensors (``sensor_type`` ending in ``Camera``)."""
    return [str(s.get("uid")) for s in data.get("sensor") or [] if str(s.get("sensor_type", "")).endswith("Camera")]


def _recorder(data: dict[str, Any], source: Path) -> dict[str, Any]:
    recorders = [f for f in ((data.get("env") or {}).get("dataset") or {}).values() if "Recorder" in str(f.get("func"))]
    if not recorders:
        raise ValueError(f"{source}: env.dataset has no LeRobot recorder to record the demonstrations with")
    params: dict[str, Any] = recorders[0].setdefault("params", {})
    return params


def _keep_cameras(data: dict[str, Any], cameras: Sequence[str], source: Path) -> None:
    available = camera_uids(data)
    if not available:
        raise ValueError(
            f"{source}: sensor: the config has no camera, and --policy camera reads images; add a Camera "
            "sensor (docs/datasets.md, 'A policy camera') or use --policy state"
        )
    missing = [c for c in cameras if c not in available]
    if missing or not cameras:
        raise ValueError(
            f"{source}: sensor: no camera {', '.join(map(repr, missing)) or '(none named)'}; "
            f"the config's cameras: {', '.join(available)}"
        )
    data["sensor"] = [s for s in data["sensor"] if s.get("uid") in cameras]


def pipeline_config(source: Path, policy: str, cameras: Sequence[str] = ()) -> dict[str, Any]:
    """The gym config to generate and evaluate with, for the ``policy`` recipe.

    ``state``: no camera, no video; the recorder must list ``environment_state``.
    ``camera``: only the cameras named in ``cameras``, recorded as videos (the recorder's
    ``use_videos`` is turned on), and no ``environment_state`` (the policy must not read
    object poses).

    Raises:
        ValueError: an unknown recipe; no recorder; ``state`` without ``environment_state``;
            ``camera`` on a config without a camera or naming one it does not have.
    """
    if policy not in POLICIES:
        raise ValueError(f"policy: unknown recipe {policy!r}; choose one of {', '.join(POLICIES)}")
    data = json.loads(source.read_text(encoding="utf-8"))
    params = _recorder(data, source)
    params["use_videos"] = policy == "camera"
    if policy == "state":
        if not params.get("environment_state"):
            raise ValueError(
                f"{source}: its LeRobot recorder must list params.environment_state (see docs/datasets.md)"
            )
        data["sensor"] = []
        return data
    _keep_cameras(data, cameras, source)
    params.pop("environment_state", None)
    return data
