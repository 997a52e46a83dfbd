"""Run by test_viewer_screens.py under Xvfb: the demo scene in the native viewer, a
screenshot after the arm swung one way and one after it swung the other way."""

from __future__ import annotations

import os
import sys
import time

import torch
from viewer_helpers import demo_env, wait_for

from embodichain_viewer import session as viewer_session
from embodichain_viewer.capture import x_screenshot

viewer_session.PUBLISH_HZ = float("inf")
env = demo_env("native")
viewer = env.unwrapped._viewer.viewer
env.reset(seed=0)
space = env.unwrapped.single_action_space
for name, frac in (("a", 0.15), ("b", 0.85)):
    target = torch.as_tensor(space.low + frac * (space.high - space.low)).expand(env.unwrapped.num_envs, -1)
    for _ in range(40):
        env.step(target.clone())
    wait_for(lambda: viewer.last is not None and viewer.last.step == env.unwrapped._viewer.steps, "the drawn step")
    time.sleep(0.5)  # the window's own thread renders the synced state
    x_screenshot(os.environ["DISPLAY"], os.path.join(sys.argv[1], f"native_{name}.png"))
env.close()
print("OK", viewer.frames)
