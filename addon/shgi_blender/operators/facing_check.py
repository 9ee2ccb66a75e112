"""Objects a bake would see from the wrong side (bpy, Blender's main thread).

A lightmap holds the light arriving at a surface's front (its normal's side). A room modelled
with its normals out (a wall's front facing away from the room) bakes the light outside it: a
floor facing down under a sky bakes the world's colour, without an error. facing_away() finds
such objects before a bake: from a few points spread over each object it casts a ray along the
normal there and one against it (Blender's Scene.ray_cast on the evaluated depsgraph). An
object whose front rays mostly escape to the world while its back rays mostly hit other objects
faces away from the scene. Hits on the object itself do not count: a closed object (a box, its
normals rightly out) sees its own inside from the back wherever it stands.

A room that is one closed mesh with its normals out looks like such a box from its own faces.
What tells the two apart is where the scene is seen from: the camera and the lamps (suns and
the world have no place) stand inside the room and see its faces from behind, while they see
a box from the front. So for an object whose front rays mostly escape, rays from the viewers to
its sample points decide when enough of them reach it: it faces away when most of those that
do see its back. That also
spares a facade seen from the street with rooms behind it, whose back rays hit the rooms'
objects. An object the viewers hardly see falls back to the rays from its own faces.

The bake warns about such an object, or with Bake Side "Facing the Scene" exports it facing the
other way (export_scene's `flipped`) so that its back is baked: every such object of the scene,
as the light the baked objects get off a surface facing away would otherwise be its outside's.

The module imports without bpy (its warning text is tested outside Blender).
"""

# Surface points sampled per object (spread over its triangles) and the share of them that
# must agree: front rays escaping and back rays hitting another object.
SAMPLES_PER_OBJECT = 16
AGREEING_SHARE = 0.5
# Rays start this far off the surface (m), along their direction, not to hit the face itself.
RAY_OFFSET = 1e-3
RAY_LENGTH = 1e6
# The fewest rays from the viewers (the camera, each lamp but suns) to an object's sample
# points that must reach it for the side they see to decide.
MIN_VIEWER_HITS = 4


def facing_away(scene, depsgraph, objects):
    """Names of `objects` (mesh objects) whose fronts see the world and backs see the scene."""
    viewers = _viewers(scene)
    return [obj.name for obj in objects if _faces_away(scene, depsgraph, obj, viewers)]


def warning(name):
    """The warning about an object facing away from the scene: what it bakes and the fixes."""
    return (f"object {name!r} faces away from the scene: its front sees the world while its "
            "back sees the other objects, so its lightmap would hold the light outside; turn "
            "its faces to the scene (Edit Mode > Mesh > Normals > Recalculate Inside, or Flip) "
            "or set Bake Side to Facing the Scene")


def turned_around(name, baked):
    """The note about an object facing away that Bake Side "Facing the Scene" turns around for
    the bake: a baked one is baked from its back, another is seen from its back."""
    what = "baked from its back" if baked else "seen by the bake from its back"
    return (f"object {name!r} faces away from the scene: {what}, the side facing the scene "
            "(Bake Side: Facing the Scene)")


def _faces_away(scene, depsgraph, obj, viewers):
    """Whether `obj`'s front rays mostly escape and, when the `viewers` see it enough, their
    rays that end on it mostly end on its back; otherwise, its back rays mostly hit other
    objects."""
    samples = _face_samples(obj.evaluated_get(depsgraph))
    if not samples:
        return False
    escaping = hitting_others = 0
    for point, normal in samples:
        escaping += _hit_object(scene, depsgraph, point, normal)[0] is None
        behind = _hit_object(scene, depsgraph, point, -normal)[0]
        hitting_others += behind is not None and behind != obj.name
    needed = AGREEING_SHARE * len(samples)
    if escaping < needed:
        return False
    fronts, backs = _sides_seen(scene, depsgraph, obj, samples, viewers)
    if fronts + backs >= MIN_VIEWER_HITS:  # seen enough: the viewers' side decides
        return backs >= AGREEING_SHARE * (fronts + backs)
    return hitting_others >= needed


def _viewers(scene):
    """World positions the scene is seen and lit from: the camera and every lamp with a place
    (not suns) that renders."""
    points = [scene.camera.matrix_world.translation] if scene.camera is not None else []
    points += [obj.matrix_world.translation for obj in scene.objects
               if obj.type == "LIGHT" and obj.data.type != "SUN" and not obj.hide_render]
    return points


def _sides_seen(scene, depsgraph, obj, samples, viewers):
    """(rays ending on `obj`'s front, rays ending on its back) of the rays from each viewer
    to each of its sample points (_face_samples') that reach `obj` first."""
    fronts = backs = 0
    for viewer in viewers:
        for point, _normal in samples:
            direction = point - viewer
            if direction.length <= RAY_OFFSET:
                continue
            direction = direction.normalized()
            name, normal = _hit_object(scene, depsgraph, viewer, direction)
            if name == obj.name:
                back = normal.dot(direction) > 0.0
                fronts, backs = fronts + (not back), backs + back
    return fronts, backs


def _face_samples(evaluated):
    """(world point, world unit normal) of SAMPLES_PER_OBJECT points spread over the evaluated
    mesh's triangles: triangles picked evenly by index, a point inside each from a
    low-discrepancy sequence (a wall of one quad is sampled all over, not at its centre only).
    Triangles of zero area are left out."""
    mesh = evaluated.data
    if hasattr(mesh, "calc_loop_triangles"):  # Blender 3.x; later versions keep them current
        mesh.calc_loop_triangles()
    triangles = mesh.loop_triangles
    if len(triangles) == 0:
        return []
    matrix = evaluated.matrix_world
    normal_matrix = matrix.to_3x3().inverted_safe().transposed()
    samples = []
    for i in range(SAMPLES_PER_OBJECT):
        triangle = triangles[i * len(triangles) // SAMPLES_PER_OBJECT]
        normal = normal_matrix @ triangle.normal
        if triangle.area > 0.0 and normal.length > 0.0:
            a, b, c = (mesh.vertices[index].co for index in triangle.vertices)
            u, v = _triangle_point(i)
            samples.append((matrix @ (a + u * (b - a) + v * (c - a)), normal.normalized()))
    return samples


def _triangle_point(i):
    """Barycentric (u, v) of the i-th point of an R2 sequence folded into a triangle."""
    u, v = (0.5 + i * 0.7548776662) % 1.0, (0.5 + i * 0.5698402910) % 1.0
    return (1.0 - u, 1.0 - v) if u + v > 1.0 else (u, v)


def _hit_object(scene, depsgraph, point, direction):
    """(name of the original object, world face normal there) of what a ray from `point`
    along `direction` (mathutils Vectors) hits first; (None, None) when it escapes."""
    hit, _location, normal, _index, obj, _matrix = scene.ray_cast(
        depsgraph, point + RAY_OFFSET * direction, direction, distance=RAY_LENGTH)
    return (obj.original.name, normal) if hit and obj is not None else (None, None)
