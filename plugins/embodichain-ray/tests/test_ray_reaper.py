"""The watchdog that ends the embedded Ray's processes with the driver (:mod:`embodichain_ray.reaper`),
on plain processes: what it kills, what it spares, and that it follows a driver killed by ``SIGKILL``."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from embodichain_ray import reaper
from ray_helpers import still_running

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="the watchdog reads /proc")

SLEEPER = [sys.executable, "-c", "import time; time.sleep(120)"]


def _spawn(*argv: str) -> subprocess.Popen:
    return subprocess.Popen(list(argv), stdin=subprocess.DEVNULL)


def test_new_descendants_are_killed_when_the_pipe_closes_and_old_and_spared_ones_are_not() -> None:
    old = _spawn(*SLEEPER)
    read_fd, write_fd = os.pipe()
    noted: dict = {}
    watcher = threading.Thread(target=lambda: noted.update(reaper.watch(os.getpid(), read_fd)), daemon=True)
    watcher.start()
    time.sleep(3 * reaper.WATCH_INTERVAL_S)  # the watch has taken its first look
    new = _spawn(*SLEEPER)
    spared = _spawn(sys.executable, "-c", "import time; time.sleep(120)", "embodichain_lerobot.writer_child")
    time.sleep(3 * reaper.WATCH_INTERVAL_S)
    os.close(write_fd)
    watcher.join(timeout=10)
    try:
        assert new.pid in noted
        assert old.pid not in noted
        assert spared.pid not in noted
        assert reaper.reap(noted, grace=0.5) == [new.pid]
        assert new.wait(timeout=10) == -9
        assert old.poll() is None
        assert spared.poll() is None
    finally:
        for proc in (old, new, spared):
            proc.kill()
            proc.wait()
        os.close(read_fd)


def test_a_driver_killed_by_sigkill_takes_its_descendants_with_it(tmp_path: Path) -> None:
    # a stand-in driver: it starts the watchdog, then a grandchild, and waits to be killed
    script = tmp_path / "driver.py"
    script.write_text(
        "import subprocess, sys, time\n"
        "from embodichain_ray.reaper import start_reaper\n"
        "start_reaper()\n"
        "time.sleep(1.0)\n"
        f"child = subprocess.Popen({SLEEPER!r})\n"
        "print(child.pid, flush=True)\n"
        "time.sleep(120)\n"
    )
    driver = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True)
    try:
        child = int(driver.stdout.readline())
        time.sleep(3 * reaper.WATCH_INTERVAL_S)
        driver.kill()
        driver.wait()
        assert still_running({child: "sleeper"}, within=reaper.GRACE_S + 5) == {}
    finally:
        driver.kill()
        driver.wait()
