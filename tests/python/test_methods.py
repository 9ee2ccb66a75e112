"""The registry of GI methods (shgi.methods) as every front end reads it: one identifier per
method with its .blend number, settings class and final passes; solvers built through it refine,
render and refuse bad settings naming the field; a method registered from Python (the
SINGLE_PROBE_TEST plugin) reaches shgi.bake and ``python -m shgi bake`` with no other edit; the
CLI given the same settings writes the same bytes as a script."""

import importlib
import json
import os
import sys

import numpy as np
import pytest

import shgi
from shgi import bake

from test_bake import room_gltf, run_cli, written_files

HERE = os.path.dirname(os.path.abspath(__file__))
# tests/python/method_plugin.py's method (it registers when imported: see the plugin fixture).
PLUGIN = "SINGLE_PROBE_TEST"


@pytest.fixture(scope="module", autouse=True)
def method_plugin():
    """The plugin module, registered for this module's tests and unregistered after them, so
    that no other test sees a method the add-on did not load with."""
    module = importlib.import_module("method_plugin")
    yield module
    shgi.unregister_method(PLUGIN)
    sys.modules.pop("method_plugin", None)


def cornell_like():
    """An inward-facing box lit by a point light, camera inside: indirect light everywhere."""
    scene = shgi.Scene()
    scene.add_material(shgi.Material(base_color=(0.7, 0.7, 0.7)))
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.uint32)
    scene.add_instance(scene.add_mesh(shgi.Mesh(positions=v, triangles=triangles)))
    light = shgi.Light(type=shgi.LightType.POINT, power=200.0)
    light.world_from_light = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 1]],
                                      np.float32)
    scene.add_light(light)
    world = shgi.World()
    world.strength = 0.0
    scene.set_world(world)
    camera = shgi.Camera()
    camera.resolution_x = camera.resolution_y = 16
    scene.set_camera(camera)
    scene.commit()
    return scene


def test_the_registry_lists_every_method_once_with_its_file_number():
    rows = {row.identifier: row for row in shgi.methods()}
    assert list(rows)[:3] == ["PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID"]
    assert [rows[m].number for m in ("PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID")] == [0, 1, 2]
    assert rows["PHOTON_LATTICE"].settings_type is shgi.PhotonLatticeSettings
    assert rows["PROBE_GRID"].settings_type is shgi.ProbeGridSettings
    assert rows["PROBE_GRID"].final_passes == 8 == bake.PROBE_GRID_PASSES
    assert not rows["PATH_TRACE"].solves_field
    # The bake source and the render method are one identifier; the old name still reads.
    assert shgi.method("PATH_TRACER") is not None
    assert shgi.method("PATH_TRACER").identifier == "PATH_TRACE"
    assert bake.sources()[:3] == ("PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID")
    numbers = [row.number for row in shgi.methods()]
    assert len(numbers) == len(set(numbers))
    with pytest.raises(ValueError, match="use one of PATH_TRACE, PHOTON_LATTICE, PROBE_GRID"):
        shgi.method("LIGHTCUTS")


@pytest.mark.parametrize("identifier", ["PHOTON_LATTICE", "PROBE_GRID", "PROPAGATION", PLUGIN])
def test_every_field_method_solves_and_renders_through_the_registry(identifier):
    scene = cornell_like()
    row = shgi.method(identifier)
    solver = shgi.make_solver(identifier, scene, shgi.default_settings(identifier, seed=2))
    assert isinstance(solver, shgi.GiSolver)
    for _ in range(row.final_passes):
        solver.refine()
    assert solver.passes == row.final_passes
    assert solver.memory_bytes > 0
    assert all(seconds >= 0.0 for _, seconds in solver.stage_seconds)
    with_field = shgi.render_preview(scene, solver.current_field(),
                                     shgi.PreviewSettings(samples=4))[0]["Combined"]
    direct_only = shgi.render_preview(scene, None, shgi.PreviewSettings(samples=4))[0]["Combined"]
    # The walls light each other: the field adds light everywhere the camera sees.
    assert with_field[..., :3].mean() > 1.1 * direct_only[..., :3].mean()


@pytest.mark.parametrize("identifier, fields, field", [
    ("PHOTON_LATTICE", {"resolution": 0}, "resolution"),
    ("PROBE_GRID", {"rays_per_probe": 0}, "rays_per_probe"),
    ("PROPAGATION", {"order": 3}, "order"),
    (PLUGIN, {"rays_per_probe": 0}, "rays_per_probe"),
])
def test_a_refused_setting_names_its_field(identifier, fields, field):
    settings = shgi.default_settings(identifier)
    for name, value in fields.items():
        setattr(settings, name, value)
    with pytest.raises(ValueError, match=field):
        shgi.make_solver(identifier, cornell_like(), settings)


def test_settings_of_another_method_or_for_the_path_tracer_are_refused():
    scene = cornell_like()
    with pytest.raises(TypeError, match="must be ProbeGridSettings, got PhotonLatticeSettings"):
        shgi.make_solver("PROBE_GRID", scene, shgi.PhotonLatticeSettings())
    with pytest.raises(ValueError, match="solves no field"):
        shgi.make_solver("PATH_TRACE", scene)


def test_registering_a_taken_or_reserved_name_or_number_is_refused():
    with pytest.raises(ValueError, match="taken by method 'PROBE_GRID'"):
        shgi.register_method("X_TEST", "X", "", 77, dict, None, aliases=["PROBE_GRID"])
    with pytest.raises(ValueError, match="number 2 is taken"):
        shgi.register_method("X_TEST", "X", "", 2, dict, None)
    with pytest.raises(ValueError, match="number 4 is taken by method 'RADIANCE_FIELD'"):
        shgi.register_method("X_TEST", "X", "", 4, dict, None)
    with pytest.raises(ValueError, match="number 3 is taken by method 'PROPAGATION'"):
        shgi.register_method("X_TEST", "X", "", 3, dict, None)
    with pytest.raises(ValueError, match="number 5 is taken by method 'INSTANT_GI'"):
        shgi.register_method("X_TEST", "X", "", 5, dict, None)
    assert "X_TEST" not in {row.identifier for row in shgi.methods()}


def test_settings_survive_json_with_every_field(method_plugin):
    grid = shgi.ProbeGridSettings(seed=3, hysteresis=0.9, visibility=False)
    volume = shgi.ProbeVolume()
    volume.resolution = (2, 3, 4)
    grid.volumes = [volume]
    lattice = shgi.PhotonLatticeSettings(caustics=shgi.CausticMode.PHOTON_MAP, photons=1234)
    for settings in (grid, lattice, method_plugin.SingleProbeSettings(rays_per_probe=7)):
        data = json.loads(json.dumps(shgi.settings_to_dict(settings)))
        again = shgi.settings_from_dict(type(settings), data)
        assert shgi.settings_to_dict(again) == shgi.settings_to_dict(settings)
    with pytest.raises(ValueError, match="has no field photon_count"):
        shgi.settings_from_dict(shgi.PhotonLatticeSettings, {"photon_count": 1})
    with pytest.raises(ValueError, match="caustics: 'GLASS' is not one of OFF, LATTICE"):
        shgi.settings_from_dict(shgi.PhotonLatticeSettings, {"caustics": "GLASS"})


def test_a_python_method_bakes_through_shgi_bake(tmp_path):
    scene = cornell_like()
    field = bake.solve_field(scene, PLUGIN, seed=1)
    assert isinstance(field, shgi.ProbeField) and field.passes == 2


def test_the_cli_bakes_a_plugin_method_and_matches_a_script_byte_for_byte(
        build_python_dir, tmp_path, method_plugin):
    """The same scene and settings through `python -m shgi bake --settings` and through
    shgi.bake in this process write identical files, for a native method and a plugin one."""
    room = tmp_path / "room.gltf"
    room.write_text(json.dumps(room_gltf()))
    cases = [("PROBE_GRID", shgi.ProbeGridSettings(seed=4, rays_per_probe=64, order=1)),
             ("PROPAGATION", shgi.PropagationSettings(seed=4, photons=20000, resolution=16)),
             (PLUGIN, method_plugin.SingleProbeSettings(rays_per_probe=64))]
    for identifier, settings in cases:
        settings_file = tmp_path / f"{identifier}.json"
        settings_file.write_text(json.dumps(shgi.settings_to_dict(settings)))
        cli_out = tmp_path / f"cli_{identifier}"
        os.environ["SHGI_METHOD_PLUGINS"] = "method_plugin"
        try:
            result = run_cli(f"{build_python_dir}{os.pathsep}{HERE}", room, "--out", cli_out,
                             "--resolution", "16", "--samples", "4", "--seed", "5",
                             "--method", identifier, "--settings", settings_file)
        finally:
            os.environ.pop("SHGI_METHOD_PLUGINS")
        assert result.returncode == 0, result.stderr

        scene = shgi.load_gltf(str(room))
        scene.commit()
        uv_set = "UVMap.001"
        jobs = bake.jobs_for_scene(scene, uv_set, 16)
        options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=4, seed=5),
                                   uv_set=uv_set)
        field = bake.solve_field(scene, identifier, settings=settings)
        script_out = tmp_path / f"script_{identifier}"
        bake.bake_scene(scene, jobs, options, str(script_out), field)
        expected = written_files(script_out)
        assert expected and written_files(cli_out) == expected, identifier
