"""The project's test and demo scenes built with bpy: the same as examples/scenes.py.

Run inside Blender: ``blender -b --factory-startup --python examples/blender_scenes.py --
[cornell_box|sun_room|two_rooms|caustics] [scale] [out.blend]`` builds one scene in a fresh
file (and saves it when a path is given); tests import the module and call ``build(name,
scale)``.

Every part matches examples/scenes.py: the same vertices (quads as one polygon, boxes as six),
Principled BSDF materials at Blender's defaults but the base colour (which are shgi.Material's
defaults), the area light (with Ray Visibility > Camera on, as the classic box shows its light),
the sun and the window portal (Cycles' area light Portal), the world colour, the camera and the
resolution times `scale`. Exporting the built scene with shgi_blender.export gives the scene
examples/scenes.py builds (tests/blender/engine_render_checks.py checks it for the first two).
caustics() alone has no twin in examples/scenes.py: the Cornell box with a glass and a gold
sphere in place of the blocks, for renderers' caustics (bench/equal_time.py).

For lightmap bakes pass ``lightmap=True`` (``-- sun_room 1 out.blend lightmap`` on the command
line), as examples/scenes.py takes it: every quad (a wall, the floor, the ceiling) then faces
into the room and gets the UV map "LightmapUV" spanning the unit square. Without it the walls
face out, as the renderers' scenes have them: a bake sees a surface's front, so a lightmap of an
outward floor would hold the world's light under it.
"""

import math
import sys

import bmesh
import bpy
from mathutils import Matrix

WHITE, RED, GREEN = (0.73, 0.73, 0.73), (0.65, 0.05, 0.05), (0.12, 0.45, 0.15)
WOOD = (0.45, 0.3, 0.18)
# Gold's base colour (its reflectance at normal incidence, as Blender's Principled BSDF takes it).
GOLD = (1.0, 0.766, 0.336)
CLEAR = (1.0, 1.0, 1.0)  # glass that does not tint what is seen through it
SKY = (0.35, 0.5, 0.8)
CORNELL_SIZE = 2.0
ROOM_X, ROOM_Y, ROOM_Z = 4.0, 4.0, 2.6
TWO_ROOMS_X, TWO_ROOMS_Y, TWO_ROOMS_Z = 6.0, 3.0, 2.5
# Principled BSDF sockets by Blender version: Blender 4.0 renamed Transmission.
TRANSMISSION_INPUTS = ("Transmission Weight", "Transmission")
WINDOW_Y, WINDOW_Z = (1.3, 2.7), (0.9, 2.1)
LIGHTMAP_UV = "LightmapUV"
# LightmapUV of a quad's corners c, c + u, c + u + v, c + v (examples/scenes.UNIT_SQUARE).
UNIT_SQUARE = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))


def reset_file():
    """An empty factory file whose scene renders at 100% with no world yet.

    read_homefile keeps the preferences (enabled add-ons); read_factory_settings would not.
    """
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    scene.render.resolution_percentage = 100
    return scene


# --- geometry (the arithmetic of examples/scenes.py) ------------------------------------------

def quad(corner, edge_u, edge_v):
    """Vertices and the one face of the parallelogram corner + [0,1]u + [0,1]v (front: u x v)."""
    c, u, v = corner, edge_u, edge_v
    vertices = [c, [c[i] + u[i] for i in range(3)], [c[i] + u[i] + v[i] for i in range(3)],
                [c[i] + v[i] for i in range(3)]]
    return vertices, [(0, 1, 2, 3)]


def box(center, sx, sy, sz, angle):
    """A closed box (six outward faces) standing on z = center[2], turned by `angle` about Z."""
    x, y = sx / 2, sy / 2
    corners = [(-x, -y, 0), (x, -y, 0), (x, y, 0), (-x, y, 0),
               (-x, -y, sz), (x, -y, sz), (x, y, sz), (-x, y, sz)]
    c, s = math.cos(angle), math.sin(angle)
    # examples/scenes.py multiplies row vectors by [[c, s, 0], [-s, c, 0], [0, 0, 1]].
    vertices = [(px * c - py * s + center[0], px * s + py * c + center[1], pz + center[2])
                for px, py, pz in corners]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    return vertices, faces


def uv_sphere(center, radius, segments, rings):
    """Vertices and faces of a UV sphere (Blender's: 2 poles, `rings` bands of `segments`
    quads, triangles at the poles): (segments * (rings - 2)) * 2 + 2 * segments triangles."""
    mesh = bmesh.new()
    bmesh.ops.create_uvsphere(mesh, u_segments=segments, v_segments=rings, radius=radius)
    vertices = [tuple(v.co[i] + center[i] for i in range(3)) for v in mesh.verts]
    faces = [tuple(v.index for v in face.verts) for face in mesh.faces]
    mesh.free()
    return vertices, faces


def look_at(eye, target, up=(0.0, 0.0, 1.0)):
    """Blender camera/light matrix_world looking down local -Z with +Y up (as scenes.look_at)."""
    forward = [t - e for t, e in zip(target, eye)]
    norm = math.sqrt(sum(f * f for f in forward))
    forward = [f / norm for f in forward]
    right = _cross(forward, up)
    norm = math.sqrt(sum(r * r for r in right))
    right = [r / norm for r in right]
    true_up = _cross(right, forward)
    return Matrix([[right[0], true_up[0], -forward[0], eye[0]],
                   [right[1], true_up[1], -forward[1], eye[1]],
                   [right[2], true_up[2], -forward[2], eye[2]],
                   [0.0, 0.0, 0.0, 1.0]])


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


# --- data blocks ------------------------------------------------------------------------------

class SceneBuilder:
    """Adds named parts to the current scene, sharing one material per name; with `lightmap`
    quads face the other way (into the room) and get LightmapUV (examples/scenes.py's)."""

    def __init__(self, lightmap=False):
        self.scene = bpy.context.scene
        self.materials = {}
        self.lightmap = lightmap

    def material(self, name, color, **inputs):
        """A Principled BSDF at Blender's defaults (= shgi.Material's) with this base colour;
        `inputs`: other sockets by name ("Metallic": 1.0), the first of a tuple of names that
        this Blender has (TRANSMISSION_INPUTS)."""
        if name not in self.materials:
            material = bpy.data.materials.new(name)
            material.use_nodes = True
            principled = material.node_tree.nodes["Principled BSDF"]
            principled.inputs["Base Color"].default_value = (*color, 1.0)
            for socket, value in inputs.items():
                principled.inputs[socket].default_value = value
            material.diffuse_color = (*color, 1.0)  # the Solid viewport colour
            self.materials[name] = material
        return self.materials[name]

    def part(self, name, geometry, material, color, smooth=False):
        vertices, faces = geometry
        is_quad = self.lightmap and len(vertices) == 4
        if is_quad:
            faces = [tuple(reversed(faces[0]))]
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(vertices, [], faces)
        if is_quad:
            layer = mesh.uv_layers.new(name=LIGHTMAP_UV)
            for loop in mesh.loops:
                layer.data[loop.index].uv = UNIT_SQUARE[loop.vertex_index]
        if smooth:
            mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
        mesh.materials.append(self.material(material, color))
        obj = bpy.data.objects.new(name, mesh)
        self.scene.collection.objects.link(obj)
        return obj

    def light(self, name, light_type, matrix_world, **properties):
        data = bpy.data.lights.new(name, light_type)
        for key, value in properties.items():
            setattr(data, key, value)
        obj = bpy.data.objects.new(name, data)
        obj.matrix_world = matrix_world
        self.scene.collection.objects.link(obj)
        return obj

    def world(self, color, strength):
        world = bpy.data.worlds.new("World")
        world.use_nodes = True
        background = world.node_tree.nodes["Background"]
        background.inputs["Color"].default_value = (*color, 1.0)
        background.inputs["Strength"].default_value = strength
        world.color = color
        self.scene.world = world

    def camera(self, eye, target, lens, width, height, scale):
        data = bpy.data.cameras.new("Camera")
        data.lens = lens
        obj = bpy.data.objects.new("Camera", data)
        obj.matrix_world = look_at(eye, target)
        self.scene.collection.objects.link(obj)
        self.scene.camera = obj
        self.scene.render.resolution_x = max(1, round(width * scale))
        self.scene.render.resolution_y = max(1, round(height * scale))


# --- the scenes -------------------------------------------------------------------------------

def cornell_box(scale=1.0, lightmap=False):
    """256 x 256 pixels times `scale` (examples/scenes.cornell_box). lightmap: walls face into
    the box, with LightmapUV."""
    b = SceneBuilder(lightmap)
    size = CORNELL_SIZE
    walls = [  # u x v points out of the box (lightmap=True turns them inwards)
        ("floor", WHITE, (-1, 0, 0), (0, size, 0), (size, 0, 0)),
        ("ceiling", WHITE, (-1, 0, size), (size, 0, 0), (0, size, 0)),
        ("back", WHITE, (-1, size, 0), (0, 0, size), (size, 0, 0)),
        ("left", RED, (-1, 0, 0), (0, 0, size), (0, size, 0)),
        ("right", GREEN, (1, 0, 0), (0, size, 0), (0, 0, size)),
    ]
    names = {WHITE: "white", RED: "red", GREEN: "green"}
    for name, color, corner, u, v in walls:
        b.part(name, quad(corner, u, v), names[color], color)
    b.part("short_block", box((0.35, 0.7, 0.0), 0.6, 0.6, 0.6, math.radians(-18)), "white", WHITE)
    b.part("tall_block", box((-0.35, 1.3, 0.0), 0.6, 0.6, 1.2, math.radians(17)), "white", WHITE)
    light = b.light("ceiling_light", "AREA", Matrix.Translation((0.0, 1.0, size - 0.01)),
                    energy=60.0, shape="SQUARE", size=0.5)
    light.visible_camera = True  # the classic box shows its light panel
    b.world((0.0, 0.0, 0.0), 0.0)
    b.camera(eye=(0, -3.6, 1.0), target=(0, 1.0, 1.0), lens=50.0, width=256, height=256,
             scale=scale)
    return b.scene


def sun_room(scale=1.0, lightmap=False):
    """256 x 192 pixels times `scale` (examples/scenes.sun_room). lightmap: walls face into the
    room, with LightmapUV."""
    b = SceneBuilder(lightmap)
    x0, y0 = -ROOM_X / 2, 0.0
    b.part("floor", quad((x0, y0, 0), (0, ROOM_Y, 0), (ROOM_X, 0, 0)), "plaster", WHITE)
    b.part("ceiling", quad((x0, y0, ROOM_Z), (ROOM_X, 0, 0), (0, ROOM_Y, 0)), "plaster", WHITE)
    b.part("back", quad((x0, ROOM_Y, 0), (0, 0, ROOM_Z), (ROOM_X, 0, 0)), "plaster", WHITE)
    b.part("right", quad((-x0, y0, 0), (0, ROOM_Y, 0), (0, 0, ROOM_Z)), "plaster", WHITE)
    b.part("front", quad((x0, y0, 0), (ROOM_X, 0, 0), (0, 0, ROOM_Z)), "plaster", WHITE)
    # Left wall (x = x0, facing +X) with the window, as four quads.
    (wy0, wy1), (wz0, wz1) = WINDOW_Y, WINDOW_Z
    left = [((x0, y0, 0), (0, 0, wz0), (0, ROOM_Y, 0)),
            ((x0, y0, wz1), (0, 0, ROOM_Z - wz1), (0, ROOM_Y, 0)),
            ((x0, y0, wz0), (0, 0, wz1 - wz0), (0, wy0, 0)),
            ((x0, wy1, wz0), (0, 0, wz1 - wz0), (0, ROOM_Y - wy1, 0))]
    for i, (corner, u, v) in enumerate(left):
        b.part(f"left_wall_{i}", quad(corner, u, v), "plaster", WHITE)
    b.part("table", box((0.6, 2.2, 0.0), 1.0, 0.7, 0.75, math.radians(10)), "wood", WOOD)
    # Sun from the upper left through the window, down onto the floor.
    sun_direction = (1.0, 0.15, -0.6)
    b.light("sun", "SUN", look_at((0, 0, 0), sun_direction), energy=6.0, angle=math.radians(1.0))
    # A portal over the window facing into the room (Cycles' area light Portal).
    center = (x0, 0.5 * (wy0 + wy1), 0.5 * (wz0 + wz1))
    portal = b.light("window_portal", "AREA", look_at(center, (center[0] + 1.0, *center[1:])),
                     shape="RECTANGLE", size=wy1 - wy0, size_y=wz1 - wz0)
    portal.data.cycles.is_portal = True
    b.world(SKY, 1.0)
    b.camera(eye=(1.7, 0.25, 1.5), target=(-0.8, 2.6, 0.8), lens=16.0, width=256, height=192,
             scale=scale)
    return b.scene


def two_rooms(scale=1.0, lightmap=False):
    """128 x 96 pixels times `scale` (examples/scenes.two_rooms): two closed rooms split by a
    wall 0.1 m thick, a bright lamp in the left one, a dim lamp in the right one where the camera
    stands facing the wall; light must not leak through it. The shell faces in (lightmap is
    accepted for the common signature and changes nothing)."""
    b = SceneBuilder()
    sx, sy, sz = TWO_ROOMS_X, TWO_ROOMS_Y, TWO_ROOMS_Z
    x0 = -sx / 2
    shell = [  # six faces of the shell, facing in
        ("floor", (x0, 0, 0), (0, sy, 0), (sx, 0, 0)),
        ("ceiling", (x0, 0, sz), (sx, 0, 0), (0, sy, 0)),
        ("front", (x0, 0, 0), (sx, 0, 0), (0, 0, sz)),
        ("back", (x0, sy, 0), (0, 0, sz), (sx, 0, 0)),
        ("left", (x0, 0, 0), (0, 0, sz), (0, sy, 0)),
        ("right", (-x0, 0, 0), (0, sy, 0), (0, 0, sz)),
    ]
    for name, corner, u, v in shell:
        b.part(name, quad(corner, u, v), "plaster", WHITE)
    b.part("wall", box((0.0, sy / 2, 0.0), 0.1, sy, sz, 0.0), "plaster", WHITE)
    for name, x, power in [("bright_lamp", -1.5, 2000.0), ("dim_lamp", 1.5, 20.0)]:
        b.light(name, "POINT", Matrix.Translation((x, sy / 2, 2.0)), energy=power,
                shadow_soft_size=0.05)
    b.world((0.0, 0.0, 0.0), 0.0)
    b.camera(eye=(2.9, 0.2, 1.4), target=(0.0, 2.2, 1.0), lens=18.0, width=128, height=96,
             scale=scale)
    return b.scene


def caustics(scale=1.0, lightmap=False):
    """256 x 256 pixels times `scale`: the Cornell box (cornell_box) with a clear glass sphere
    (IOR 1.5) and a gold sphere (metallic, roughness 0.2) in place of the blocks; the glass
    sphere focuses the ceiling light into a caustic on the floor."""
    scene = cornell_box(scale, lightmap)
    for name in ("short_block", "tall_block"):
        bpy.data.objects.remove(bpy.data.objects[name], do_unlink=True)
    b = SceneBuilder(lightmap)
    transmission = next(name for name in TRANSMISSION_INPUTS if _principled_has(name))
    b.material("glass", CLEAR, **{"Roughness": 0.0, "IOR": 1.5, transmission: 1.0})
    b.material("gold", GOLD, **{"Metallic": 1.0, "Roughness": 0.2})
    b.part("glass_sphere", uv_sphere((0.4, 0.7, 0.4), 0.4, 64, 32), "glass", CLEAR, smooth=True)
    b.part("gold_sphere", uv_sphere((-0.4, 1.3, 0.4), 0.4, 64, 32), "gold", GOLD, smooth=True)
    return scene


def _principled_has(socket):
    """True when this Blender's Principled BSDF has an input named `socket`."""
    material = bpy.data.materials.new("socket_probe")
    material.use_nodes = True
    found = socket in material.node_tree.nodes["Principled BSDF"].inputs
    bpy.data.materials.remove(material)
    return found


SCENES = {"cornell_box": cornell_box, "sun_room": sun_room, "two_rooms": two_rooms,
          "caustics": caustics}


def build(name, scale=1.0, lightmap=False):
    """Builds scene `name` (a key of SCENES) in a fresh file; returns the scene.
    lightmap: quads face into the room, with LightmapUV (for bakes)."""
    reset_file()
    return SCENES[name](scale, lightmap)


def main():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    name = args[0] if args else "cornell_box"
    scale = float(args[1]) if len(args) > 1 else 1.0
    build(name, scale, lightmap=args[3:4] == ["lightmap"])
    if len(args) > 2:
        bpy.ops.wm.save_as_mainfile(filepath=args[2])


if __name__ == "__main__":
    main()
