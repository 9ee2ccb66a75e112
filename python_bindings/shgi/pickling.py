"""Pickling of the native scene and its settings, so that a Scene built in one process (the
add-on's export, a script's) can be baked in another: a Dask worker of a farm bake
(shgi.farm.bake_scene_on_cluster), a multiprocessing pool.

``pickle.dumps(scene)`` holds what the Scene was built from (its meshes as the scene keeps them,
after dropping degenerate triangles; instances, materials, textures, lights, world, camera) and
``pickle.loads`` builds an uncommitted Scene from it with the same add_* calls, so the copy
renders and bakes exactly as the original does (tests/python/test_pickling.py). BVHs, committed
state and mesh reports do not travel: commit the copy.

The settings structs (LightmapSettings, each method's settings, Material, Light, World, Camera,
...) pickle field by field, by their property names (shgi.settings_to_dict's fields), so a field
added to a struct travels without an edit here.

Unpickling runs the constructors and setters, which validate as for any caller; a pickle itself
can run code, as every pickle can: load only pickles you made (a farm's own tasks).
"""

import copyreg

from . import _shgi
from . import method_registry as _methods

# Default-constructible structs that pickle as their settable fields; every native method's
# settings type joins them (register_structs). A Python method's dataclass settings pickle as
# they are.
_STRUCTS = ("Material", "Light", "World", "Camera", "LightmapSettings", "LightmapFilterSettings",
            "TexelRasterSettings", "UnoccludeSettings", "PathTracerSettings", "PreviewSettings",
            "ProbeLookupSettings", "ProbeVolume")


def _rebuild_struct(cls, state: dict):
    value = cls()
    for name, field in state.items():
        setattr(value, name, field)
    return value


def _reduce_struct(value):
    return _rebuild_struct, (type(value), {name: getattr(value, name)
                                           for name in _methods._fields(type(value))})


def _rebuild_mesh(state: dict):
    return _shgi.Mesh(**state)


def _reduce_mesh(mesh):
    return _rebuild_mesh, ({
        "positions": mesh.positions, "triangles": mesh.triangles,
        "normals": mesh.normals if len(mesh.normals) else None,
        "uvs": mesh.uv_sets or None,
        "material_indices": mesh.material_indices if len(mesh.material_indices) else None,
        "name": mesh.name,
        "tangents": mesh.tangents if len(mesh.tangents) else None},)


def _rebuild_texture(pixels, name: str):
    return _shgi.Texture(pixels, name)


def _reduce_texture(texture):
    return _rebuild_texture, (texture.pixels, texture.name)


def _rebuild_scene(state: dict):
    scene = _shgi.Scene()
    for mesh in state["meshes"]:
        scene.add_mesh(mesh)
    for mesh_id, matrix, name in state["instances"]:
        scene.add_instance(mesh_id, matrix, name)
    for material in state["materials"]:
        scene.add_material(material)
    for texture in state["textures"]:
        scene.add_texture(texture)
    for light in state["lights"]:
        scene.add_light(light)
    scene.set_world(state["world"])
    if state["camera"] is not None:
        scene.set_camera(state["camera"])
    return scene


def _reduce_scene(scene):
    return _rebuild_scene, ({
        "meshes": scene.meshes,
        "instances": [(instance.mesh_id, instance.world_from_object, instance.name)
                      for instance in scene.instances],
        "materials": scene.materials, "textures": scene.textures, "lights": scene.lights,
        "world": scene.world, "camera": scene.camera if scene.has_camera else None},)


def register_structs() -> None:
    """Registers the reducers (copyreg) of the scene types, the structs above and every native
    method's settings type; shgi calls it on import."""
    for name in _STRUCTS:
        copyreg.pickle(getattr(_shgi, name), _reduce_struct)
    for row in _shgi.native_methods():  # not methods(): no plugin imports at shgi's import
        copyreg.pickle(getattr(_shgi, row.settings_type), _reduce_struct)
    copyreg.pickle(_shgi.Mesh, _reduce_mesh)
    copyreg.pickle(_shgi.Texture, _reduce_texture)
    copyreg.pickle(_shgi.Scene, _reduce_scene)
