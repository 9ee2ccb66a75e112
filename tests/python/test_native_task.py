"""The add-on's NativeTask (engine/native_task.py, bpy-free) with the real shgi.Progress."""

import pathlib
import sys
import threading
import time

import pytest

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "addon"))
from shgi_blender.engine.native_task import NativeTask  # noqa: E402


class UntilCancelled(NativeTask):
    """Work that runs until its Progress is cancelled, as a long native call does."""

    def __init__(self):
        super().__init__(shgi, "shgi-test-task")
        self.began = threading.Event()

    def _work(self):
        self.began.set()
        while not self.progress.cancelled:
            time.sleep(0.001)
        raise shgi.Cancelled("cancelled")


def test_cancel_ends_the_task():
    task = UntilCancelled().start()
    assert task.began.wait(5)
    assert task.running
    task.cancel()
    assert task.wait(5)
    assert task.cancelled and task.error is None and not task.running


def test_a_keyboard_interrupt_inside_start_cancels_the_started_worker():
    task = UntilCancelled()
    thread_start = task._thread.start

    def start_then_interrupted():
        thread_start()          # the worker runs...
        task.began.wait(5)
        raise KeyboardInterrupt  # ...and Ctrl-C lands before start() returns

    task._thread.start = start_then_interrupted
    with pytest.raises(KeyboardInterrupt):
        task.start()
    # Nobody holds the task to cancel it: start() did.
    assert task.wait(5), "the worker was left running"
    assert task.cancelled
