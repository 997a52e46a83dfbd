"""embodichain-tasks: task envs for embodichain-core.

* ``ModularEnv-v1``: the seed tutorial (:mod:`embodichain_tasks.tutorials.modular_env`).
* ``PushCube-v1``: RL, a 7-DoF arm pushes a cube to a goal (:mod:`embodichain_tasks.rl.push_cube`),
  with a pure-torch PPO script (:mod:`embodichain_tasks.rl.ppo`).
* ``OpenDrawer-v1``, ``PickFork-v1``: IL tasks with scripted W1 demos (:mod:`embodichain_tasks.il`).

Importing the package is cheap; the plugin (:mod:`embodichain_tasks.plugin`) registers the
task ids lazily, so ``gym.make("PushCube-v1")`` works after ``import embodichain_core``.
"""

__version__ = "0.1.0"
