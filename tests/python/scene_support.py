"""What tests outside Blender share: the project's example scenes (examples/scenes.py) as they
use them, and a guard against calls that deadlock."""

import threading


def committed(builder):
    """The shgi.Scene of an examples/scenes.py builder, committed and ready to render."""
    builder.scene.commit()
    return builder.scene


def finishes_in_a_thread(call, timeout=30.0):
    """Runs call() in a daemon thread: a deadlock fails the test instead of hanging the run."""
    outcome = {}

    def run():
        try:
            outcome["result"] = call()
        except Exception as error:  # reported by the caller's assertions
            outcome["error"] = error

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(timeout)
    assert not worker.is_alive(), "the call deadlocked"
    if "error" in outcome:
        raise outcome["error"]
    return outcome.get("result")
