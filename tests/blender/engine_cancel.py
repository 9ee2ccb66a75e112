"""Esc stops an SHGI render promptly and keeps the samples finished before it.

1. Real F12 (bpy.ops.render.render) of a path-traced render of 10^6 samples per pixel: a timer
   thread sends SIGINT to Blender, which in background mode is Blender's own Esc (it sets the
   break flag that RenderEngine.test_break reads and prints "Sent an internal break event").
   A second SIGINT would kill Blender, so this is done once per process. Under the bpy module
   SIGINT raises KeyboardInterrupt in the engine's polling loop, which stops the render as Esc.
2. The engine's F12 code (engine/final_render.py) driven directly with a stub RenderEngine whose
   test_break turns True after a delay, once while the photon lattice is being solved and once
   while the path tracer samples.
3. The same stub breaking during the scene export: HEAVY_OBJECTS objects of HEAVY_GRID^2 quads
   each (a modifier makes each one its own geometry to read), seconds of export.
4. Under the bpy module only, case 1 again with a SIGINT handler that raises nothing, as when
   the KeyboardInterrupt is swallowed before it reaches the engine.
Each render must end within CANCEL_LATENCY seconds of the break (timed by a LatencyClock: the
seconds the host stole from this machine's CPUs do not count), report no error, record
`cancelled`, and (for the sampling cases) keep a partial image; the export case must not have
started the solver. Prints ENGINE_CANCEL_OK.
"""

import json
import os
import signal
import sys
import tempfile
import threading
from types import SimpleNamespace

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
from blender_test_setup import results_path  # noqa: E402
from latency_clock import LatencyClock  # noqa: E402

import bpy  # noqa: E402
from shgi_blender.engine import final_render  # noqa: E402

SCALE = 0.25
HUGE_SAMPLES = 1_000_000
HUGE_PHOTONS = 200_000_000
BREAK_AFTER_SECONDS = 1.5
HEAVY_OBJECTS = 200
HEAVY_GRID = 100  # quads per side: 19,602 triangles per object
EXPORT_BREAK_AFTER_SECONDS = 0.5
# docs/architecture.md: a cancelled native call returns within 0.2 s; the engine polls every 0.05 s.
CANCEL_LATENCY = 0.5
# After this long a render that missed the SIGINT is ended and the test fails.
WATCHDOG_SECONDS = 20.0


class StubEngine:
    """The RenderEngine calls final_render makes, recorded; test_break turns True `break_after`
    seconds after start(), when a timer thread "presses Esc" and starts `clock`."""

    def __init__(self, width, height, break_after):
        self.resolution_x, self.resolution_y = width, height
        self.reports = []
        self.combined = SimpleNamespace(name="Combined", channels=4, rect=None)
        self.ended = False
        self.polled_after_break = False  # test_break was asked once the break was due
        self.clock = None  # a LatencyClock from the moment of the break
        self._broken = threading.Event()
        self._timer = threading.Timer(break_after, self._press_esc)

    def start(self):
        self._timer.start()

    def stop(self):
        self._timer.cancel()
        self._timer.join()

    def _press_esc(self):
        self.clock = LatencyClock()
        self._broken.set()

    def test_break(self):
        broken = self._broken.is_set()
        self.polled_after_break = self.polled_after_break or broken
        return broken

    def begin_result(self, x, y, width, height, layer=""):
        # Blender's RenderResult: its size and the view layer's passes.
        return SimpleNamespace(resolution_x=width, resolution_y=height,
                               layers=[SimpleNamespace(passes=[self.combined])])

    def update_result(self, result):
        pass

    def end_result(self, result):
        self.ended = True

    def update_progress(self, fraction):
        pass

    def update_stats(self, stats, info):
        pass

    def update_memory_stats(self, memory_used=0.0, memory_peak=0.0):
        pass

    def report(self, kind, message):
        self.reports.append((sorted(kind)[0], message))

    def error_set(self, message):
        self.reports.append(("ERROR_SET", message))


def check_record(what, record, latency, expect_image, stage=None):
    if record["errors"] or not record["cancelled"]:
        raise AssertionError(f"{what}: not a clean cancel: {record}")
    stage = stage or ("render" if expect_image else "solve")
    later = {"export": ("commit", "solve", "render"), "solve": ("render",), "render": ()}[stage]
    if stage not in record["timings"] or any(name in record["timings"] for name in later):
        raise AssertionError(f"{what}: the break did not land in the {stage} stage: "
                             f"{record['timings']}")
    if latency.seconds > CANCEL_LATENCY:
        raise AssertionError(f"{what}: ended {latency} after the break (> {CANCEL_LATENCY} s)")
    if expect_image and not 0 < record["samples"] < HUGE_SAMPLES:
        raise AssertionError(f"{what}: {record['samples']} samples kept; expected a partial "
                             "image")


def row_of(latency):
    """The results JSON's figures of a Latency: its seconds, wall time and steal."""
    return {"latency": latency.seconds, **latency._asdict()}


def add_heavy_objects(scene):
    """HEAVY_OBJECTS small grids inside the box, each with a modifier (exported one by one)."""
    n = HEAVY_GRID + 1
    vertices = [(0.2 * x / HEAVY_GRID, 0.2 * y / HEAVY_GRID, 0.0) for y in range(n)
                for x in range(n)]
    faces = [(y * n + x, y * n + x + 1, (y + 1) * n + x + 1, (y + 1) * n + x)
             for y in range(HEAVY_GRID) for x in range(HEAVY_GRID)]
    mesh = bpy.data.meshes.new("heavy_grid")
    mesh.from_pydata(vertices, [], faces)
    for i in range(HEAVY_OBJECTS):
        obj = bpy.data.objects.new(f"heavy_{i}", mesh)
        obj.location = (-0.4 + 0.04 * (i % 20), -0.4 + 0.08 * (i // 20), 0.05)
        obj.modifiers.new("Triangulate", "TRIANGULATE")
        scene.collection.objects.link(obj)


def cancel_with_stub(method, during_export=False):
    """final_render with a stub engine; returns (record, latency in s)."""
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.method = method
    scene.shgi.samples = HUGE_SAMPLES
    scene.shgi.photon_lattice.photons = HUGE_PHOTONS
    if during_export:
        add_heavy_objects(scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()  # evaluated before the timer starts
    after = EXPORT_BREAK_AFTER_SECONDS if during_export else BREAK_AFTER_SECONDS
    stub = StubEngine(scene.render.resolution_x, scene.render.resolution_y, after)
    stub.start()
    try:
        final_render.render(stub, depsgraph)
    finally:
        stub.stop()
    if stub.clock is None:
        raise AssertionError(f"stub {method}: the render ended before the break, {after} s in")
    latency = stub.clock.read()  # from when Esc was "pressed"
    if stub.ended == during_export:  # an export cancelled before any result was begun
        raise AssertionError(f"stub {method}: end_result called: {stub.ended}")
    return final_render.last_render(), latency, stub


def cancel_f12_with_sigint(tmpdir):
    """Real F12 interrupted by Blender's background-mode Esc (SIGINT)."""
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.method = "PATH_TRACE"
    scene.shgi.samples = HUGE_SAMPLES
    sent = {}
    returned = threading.Event()

    def send_break():
        sent["clock"] = LatencyClock()
        os.kill(os.getpid(), signal.SIGINT)
        # A Ctrl-C the render missed would leave it sampling for hours: end it now (a second
        # SIGINT: another KeyboardInterrupt under the bpy module, the end of Blender 3.4.1) and
        # fail below, rather than wait for the test runner's timeout.
        if not returned.wait(WATCHDOG_SECONDS):
            sent["missed"] = True
            os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(BREAK_AFTER_SECONDS, send_break)
    timer.start()
    try:
        passes = common.render_f12(scene, "SHGI", os.path.join(tmpdir, "cancelled.exr"))
    finally:
        returned.set()
    latency = sent["clock"].read()
    timer.join()
    if sent.get("missed"):
        raise AssertionError(f"F12 + SIGINT: the render was still running {WATCHDOG_SECONDS} s "
                             "after the SIGINT")
    return final_render.last_render(), latency, common.mean_rgb(passes["Combined"])


def main():
    out = results_path("shgi_engine_cancel.json")
    results = {}
    for method, expect_image in (("PHOTON_LATTICE", False), ("PATH_TRACE", True)):
        record, latency, stub = cancel_with_stub(method)
        check_record(f"stub {method}", record, latency, expect_image)
        if expect_image and stub.combined.rect is None:
            raise AssertionError("stub PATH_TRACE: the partial image was not written")
        results[f"stub {method}"] = {**row_of(latency), "samples": record["samples"],
                                     "stage_seconds": record["timings"]}
    record, latency, stub = cancel_with_stub("PHOTON_LATTICE", during_export=True)
    check_record("stub export", record, latency, False, stage="export")
    if not stub.polled_after_break:  # the export's own duration starts after the stub's clock
        raise AssertionError(f"stub export: the export ended before the break: {record}")
    results["stub export"] = {**row_of(latency), "samples": record["samples"],
                              "stage_seconds": record["timings"]}
    with tempfile.TemporaryDirectory(prefix="shgi_cancel_") as tmpdir:
        record, latency, mean = cancel_f12_with_sigint(tmpdir)
    check_record("F12 + SIGINT", record, latency, True)
    if not mean > 0.0:
        raise AssertionError("F12 + SIGINT: the partial image is black")
    results["F12 SIGINT PATH_TRACE"] = {**row_of(latency), "samples": record["samples"],
                                        "stage_seconds": record["timings"]}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # the bpy module
        # 4. A Ctrl-C whose KeyboardInterrupt never reaches the engine (a finaliser or a
        # callback Blender calls swallowed it; here, a handler that raises nothing): the
        # engine still sees the signal (keyboard_interrupt.sigint_watch).
        signal.signal(signal.SIGINT, lambda *_: None)
        try:
            with tempfile.TemporaryDirectory(prefix="shgi_cancel_") as tmpdir:
                record, latency, mean = cancel_f12_with_sigint(tmpdir)
        finally:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        check_record("F12 + swallowed SIGINT", record, latency, True)
        results["F12 swallowed SIGINT"] = {**row_of(latency), "samples": record["samples"],
                                           "stage_seconds": record["timings"]}
    for name, row in results.items():
        print(f"{name:<24} ended {1000 * row['latency']:6.1f} ms after the break "
              f"({1000 * row['stolen']:.1f} ms stolen by the host), {row['samples']} samples "
              "kept", flush=True)
    with open(out, "w") as f:
        json.dump(results, f, indent=1)
    print("ENGINE_CANCEL_OK")


main()
