"""Every large allocation is estimated first and refused with a MemoryError naming the setting,
the bytes it needs and the bytes the process may still allocate (docs/robustness-memory.md):
rasterize_texels at 16384^2 ran 21 s into std::bad_alloc, and photons = 2**36 ran 52 s to 7 GB,
because budgets were shares of the total RAM, not of what the process may really use."""

import os
import re
import subprocess
import sys
import textwrap

import numpy as np

import pytest

import shgi
from blender_support import REPO_ROOT
from scene_support import committed
from test_bake import plane_scene

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/scenes.py, the project's test scenes)

NEEDS = re.compile(r"needs [\d.]+ [kMGTPE]?B \((\d+) bytes\); this process may use [\d.]+ "
                   r"[kMGTPE]?B \((\d+) bytes\) more \(limited by ([^;]+);")


def needed_and_allowed(error):
    """(bytes needed, bytes the process may use, what limits it) from a MemoryError's text."""
    found = NEEDS.search(str(error))
    assert found, f"no byte counts in: {error}"
    return int(found.group(1)), int(found.group(2)), found.group(3)


def run_limited(code, address_space):
    """Runs `code` in a child Python whose RLIMIT_AS is `address_space` bytes (set before shgi
    is imported); returns its stdout."""
    script = textwrap.dedent(f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, ({address_space}, {address_space}))
        import sys
        sys.path[:0] = {[str(REPO_ROOT / "tests" / "python"), str(REPO_ROOT / "examples")]!r}
        import shgi
    """) + textwrap.dedent(code)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_memory_limits_are_the_smallest_of_rlimit_cgroup_and_free_memory():
    limits = shgi.memory_limits()
    bounds = [limits[k] for k in ("address_space_left", "cgroup_left", "available")
              if limits[k] is not None]
    assert bounds, "MemAvailable is always known on Linux"
    assert limits["allowed"] == min(bounds)
    assert limits["available"] > 0


def test_a_fake_rlimit_as_bounds_what_the_process_may_allocate():
    limit = 6 * 2**30
    out = run_limited("""
        limits = shgi.memory_limits()
        with open("/proc/self/statm") as statm:
            virtual = int(statm.read().split()[0]) * __import__("os").sysconf("SC_PAGE_SIZE")
        print(limits["address_space_left"], limits["allowed"], limits["limited_by"], virtual,
              sep="|")
    """, limit)
    left, allowed, limited_by, virtual = out.strip().split("|")
    left, allowed, virtual = int(left), int(allowed), int(virtual)
    # RLIMIT_AS minus the virtual size already mapped (read a moment apart: within 64 MiB).
    assert 0 < left <= limit - virtual + 64 * 2**20
    assert left >= limit - virtual - 64 * 2**20
    assert allowed <= left
    if allowed == left:
        assert limited_by == "RLIMIT_AS"


def test_rasterize_under_a_fake_rlimit_as_is_refused_naming_it():
    out = run_limited("""
        from test_bake import plane_scene
        scene = plane_scene()
        try:
            shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(
                width=4096, height=4096, samples_per_axis=2))
            print("rasterized")
        except MemoryError as error:
            print(error)
    """, 6 * 2**30)
    assert "TexelRasterSettings.width x height = 4096 x 4096 with 4 samples per texel" in out
    needed, allowed, limited_by = needed_and_allowed(out)
    assert needed > 6 * 2**30 > allowed
    assert limited_by == "RLIMIT_AS"


@pytest.mark.parametrize("side, per_axis", [(16384, 16), (4096, 16), (16384, 2)])
def test_rasterize_beyond_memory_is_refused_before_allocating(side, per_axis):
    """At 16384^2 (or 4096^2 with 16 x 16 samples) the samples alone are hundreds of GB."""
    scene = plane_scene()
    settings = shgi.TexelRasterSettings(width=side, height=side, samples_per_axis=per_axis)
    stages = []
    progress = shgi.Progress(lambda fraction, stage: stages.append(stage), 0.0)
    with pytest.raises(MemoryError) as caught:
        shgi.rasterize_texels(scene, 0, settings, progress=progress)
    message = str(caught.value)
    assert (f"TexelRasterSettings.width x height = {side} x {side} with "
            f"{per_axis * per_axis} samples per texel") in message
    assert "mesh 'plane' cover 100% of the lightmap" in message
    assert message.endswith("lower the resolution (width, height) or samples_per_axis, "
                            "or bake in tiles")
    needed, allowed, _ = needed_and_allowed(message)
    assert needed > allowed
    # Estimated, not attempted: refused before the rasterizing stage began.
    assert "rasterizing texels" not in stages


def test_rasterize_reports_progress_and_stops_at_a_cancel_inside_one_large_triangle():
    """One triangle covering half of the map was one chunk of work: progress stood still and a
    cancel waited for the whole triangle. Progress now moves per texel row."""
    scene = plane_scene()
    seen = []

    def cancel_once_moving(fraction, stage):
        seen.append((fraction, stage))
        if fraction > 0.0:
            progress.cancel()

    progress = shgi.Progress(cancel_once_moving, 0.0)
    with pytest.raises(shgi.Cancelled):
        shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(width=2048, height=2048),
                              progress=progress)
    moving = [fraction for fraction, stage in seen if fraction > 0.0]
    assert moving and moving[0] < 0.1
    assert {stage for _, stage in seen} == {"rasterizing texels"}


def test_a_photon_pass_far_beyond_memory_is_refused_after_its_pilot_block():
    scene = committed(scenes.cornell_box(0.1))
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(resolution=8, photons=2**36))
    fractions = []
    progress = shgi.Progress(lambda fraction, stage: fractions.append(fraction), 0.0)
    with pytest.raises(MemoryError) as caught:
        lattice.solve(progress=progress)
    message = str(caught.value)
    assert message.startswith("PhotonLatticeSettings.photons = 68719476736 (the first 262144 "
                              "photons stored")
    assert message.endswith("lower PhotonLatticeSettings.photons (or trace more passes of "
                            "fewer photons)")
    needed, allowed, _ = needed_and_allowed(message)
    assert needed > allowed
    assert lattice.passes == 0
    assert max(fractions) < 1e-4  # only the pilot block of 2**18 photons was traced


def test_a_film_beyond_memory_names_the_camera_resolution():
    scene = plane_scene()
    scene.set_camera(shgi.Camera(resolution_x=46340, resolution_y=46340))
    scene.commit()
    with pytest.raises(MemoryError) as caught:
        shgi.PathTracer(scene)
    message = str(caught.value)
    assert "the camera resolution (film) 46340 x 46340 pixels with 16 passes" in message
    assert message.endswith("lower the camera's resolution_x / resolution_y "
                            "(or Blender's resolution %)")
    needed, allowed, _ = needed_and_allowed(message)
    assert needed == 4 * 46340 * 46340 * 16 * 12 and needed > allowed


def test_commit_budget_is_capped_by_what_the_process_may_allocate():
    """An explicit memory_budget_bytes larger than the memory left no longer lets the BVH
    build run into the OOM killer: the budget is capped by memory_limits()['allowed']."""
    scene = plane_scene()
    out = run_limited("""
        from test_bake import plane_scene
        scene = plane_scene()
        scene.commit(memory_budget_bytes=2**60)
        print("committed", scene.committed)
    """, 6 * 2**30)
    assert out.split() == ["committed", "True"]
    # A moved instance makes the next commit build the top-level BVH (a commit that changes no
    # geometry builds nothing, so no budget can stop it).
    scene.set_instance_transform(0, np.eye(4))
    with pytest.raises(MemoryError) as caught:
        scene.commit(memory_budget_bytes=1000)
    message = str(caught.value)
    assert "exceeded the memory budget: budget 1000 bytes" in message
    assert "raise memory_budget_bytes (0 = 75% of what the process may still allocate: " \
           "RLIMIT_AS / cgroup / free memory)" in message
    assert not scene.committed


def test_an_sh_lattice_beyond_a_fake_rlimit_as_is_refused_naming_its_cells():
    out = run_limited("""
        import scenes
        from scene_support import committed
        scene = committed(scenes.cornell_box(0.1))
        try:
            shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(resolution=400))
            print("allocated")
        except MemoryError as error:
            print(error)
    """, 6 * 2**30)
    assert out.startswith("ShLattice: resolution = 400 gives 400 x 400 x 400 = 64000000 cells "
                          "of 117 bytes (order 2) needs 7.5 GB (7488000000 bytes)")
    needed, allowed, limited_by = needed_and_allowed(out)
    assert needed == 64000000 * 117 > allowed
    assert limited_by == "RLIMIT_AS"
    assert out.strip().endswith("lower the resolution")


def test_a_photon_lattice_whose_lattices_fit_one_by_one_but_not_with_their_sums_is_refused():
    """The global lattice fits what is left; the per-pass sums beside it (a copy) do not: the
    lattice checks their sum before copying, naming both resolutions."""
    out = run_limited("""
        import scenes
        from scene_support import committed
        scene = committed(scenes.cornell_box(0.1))
        try:
            shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
                resolution=260, caustics=shgi.CausticMode.OFF))
            print("allocated")
        except MemoryError as error:
            print(error)
    """, int(3.5 * 2**30))
    assert out.startswith("PhotonLattice: the per-pass sums beside the lattices (resolution 260, "
                          "caustic_resolution 64) needs"), out
    needed, allowed, limited_by = needed_and_allowed(out)
    assert allowed < needed and limited_by == "RLIMIT_AS"
    assert out.strip().endswith("lower resolution or caustic_resolution")
