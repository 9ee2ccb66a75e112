"""What tests outside Blender share: the project's example scenes (examples/scenes.py) as they
use them, their path-traced references, and a guard against calls that deadlock."""

import threading

import shgi

_REFERENCES = {}


def committed(builder):
    """The shgi.Scene of an examples/scenes.py builder, committed and ready to render."""
    builder.scene.commit()
    return builder.scene


def path_traced_reference(make_scene, scale, samples, seed=11):
    """(committed scene, path-traced passes) of `make_scene(scale)` (an examples/scenes.py
    function) at `samples` per pixel, rendered once per session: the photon lattice's and the
    probe grid's agreement tests compare against the same references."""
    key = (make_scene, scale, samples, seed)
    if key not in _REFERENCES:
        scene = committed(make_scene(scale))
        _REFERENCES[key] = scene, shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=samples, seed=seed))
    return _REFERENCES[key]


_FIELD_RENDERS = {}


def field_agreement(method, make_scene, scale, samples, solve, seed=5):
    """(path-traced reference passes, (preview passes, timings) over the field that
    `solve(committed scene)` returns) of `make_scene(scale)`, once per session and `method` (a
    name for the cache): the field methods' agreement tests."""
    key = (method, make_scene, scale, samples)
    if key not in _FIELD_RENDERS:
        scene, reference = path_traced_reference(make_scene, scale, samples)
        field = solve(scene)
        _FIELD_RENDERS[key] = reference, shgi.render_preview(scene, field,
                                                              shgi.PreviewSettings(seed=seed))
    return _FIELD_RENDERS[key]


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
