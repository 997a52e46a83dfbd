"""embodichain-ray: ``embodichain generate`` scales scripted data generation out on Ray.

Workers are Ray actors that each own one env (``K`` parallel envs), take episode
indices from the driver's queue and record them into their own LeRobot shard; the
driver merges the shards with lerobot's aggregation into one dataset ordered by
episode index. The core never imports Ray.
"""

__version__ = "0.1.0"
