"""Objects a bake would see from the wrong side (bpy, Blender's main thread).

A lightmap holds the light arriving at a surface's front (its normal's side). A room modelled
with its normals out (a wall's front facing away from the room) bakes the light outside it: a
floor facing down under a sky bakes the world's colour, without an error. facing_away() finds
such objects before a bake: from a few face centres of each object it casts a ray along the
face's normal and one against it (Blender's Scene.ray_cast on the evaluated depsgraph). An
object whose front rays mostly escape to the world while its back rays mostly hit other objects
faces away from the scene. Hits on the object itself do not count: a closed object (a box, its
normals rightly out) sees its own inside from the back wherever it stands.

A room that is one closed mesh with its normals out looks like such a box and is not found.
The module imports without bpy (its warning text is tested outside Blender).
"""

# Face centres sampled per object (evenly over its faces) and the share of them that must
# agree: front rays escaping and back rays hitting another object.
SAMPLES_PER_OBJECT = 16
AGREEING_SHARE = 0.5
# Rays start this far off the surface (m), along their direction, not to hit the face itself.
RAY_OFFSET = 1e-3
RAY_LENGTH = 1e6


def facing_away(scene, depsgraph, objects):
    """Names of `objects` (mesh objects) whose fronts see the world and backs see the scene."""
    return [obj.name for obj in objects if _faces_away(scene, depsgraph, obj)]


def warning(name):
    """The warning about an object facing away from the scene: what it bakes and the fix."""
    return (f"object {name!r} faces away from the scene: its front sees the world while its "
            "back sees the other objects, so its lightmap would hold the light outside; turn "
            "its faces to the scene (Edit Mode > Mesh > Normals > Recalculate Inside, or Flip)")


def _faces_away(scene, depsgraph, obj):
    samples = _face_samples(obj.evaluated_get(depsgraph))
    if not samples:
        return False
    escaping = hitting_others = 0
    for point, normal in samples:
        escaping += _hit_object(scene, depsgraph, point, normal) is None
        behind = _hit_object(scene, depsgraph, point, -normal)
        hitting_others += behind is not None and behind != obj.name
    needed = AGREEING_SHARE * len(samples)
    return escaping >= needed and hitting_others >= needed


def _face_samples(evaluated):
    """(world centre, world unit normal) of up to SAMPLES_PER_OBJECT faces, evenly spread over
    the evaluated mesh's faces (faces of zero area left out)."""
    mesh = evaluated.data
    count = len(mesh.polygons)
    if count == 0:
        return []
    matrix = evaluated.matrix_world
    normal_matrix = matrix.to_3x3().inverted_safe().transposed()
    picks = sorted({i * count // SAMPLES_PER_OBJECT for i in range(SAMPLES_PER_OBJECT)})
    samples = []
    for index in picks:
        polygon = mesh.polygons[index]
        normal = normal_matrix @ polygon.normal
        if polygon.area > 0.0 and normal.length > 0.0:
            samples.append((matrix @ polygon.center, normal.normalized()))
    return samples


def _hit_object(scene, depsgraph, point, direction):
    """Name of the (original) object a ray from `point` along `direction` (mathutils
    Vectors) hits first; None when it escapes to the world."""
    hit, _location, _normal, _index, obj, _matrix = scene.ray_cast(
        depsgraph, point + RAY_OFFSET * direction, direction, distance=RAY_LENGTH)
    return obj.original.name if hit and obj is not None else None
