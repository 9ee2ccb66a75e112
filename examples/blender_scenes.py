"""The project's test and demo scenes built with bpy: the same as examples/scenes.py.

Run inside Blender: ``blender -b --factory-startup --python examples/blender_scenes.py --
[cornell_box|sun_room] [scale] [out.blend]`` builds one scene in a fresh file (and saves it when
a path is given); tests import the module and call ``build(name, scale)``.

Every part matches examples/scenes.py: the same vertices (quads as one polygon, boxes as six),
Principled BSDF materials at Blender's defaults but the base colour (which are shgi.Material's
defaults), the area light (with Ray Visibility > Camera on, as the classic box shows its light),
the sun and the window portal (Cycles' area light Portal), the world colour, the camera and the
resolution times `scale`. Exporting the built scene with shgi_blender.export gives the scene
examples/scenes.py builds (tests/blender/engine_render_checks.py checks it).

For lightmap bakes pass ``lightmap=True`` (``-- sun_room 1 out.blend lightmap`` on the command
line), as examples/scenes.py takes it: every quad (a wall, the floor, the ceiling) then faces
into the room and gets the UV map "LightmapUV" spanning the unit square. Without it the walls
face out, as the renderers' scenes have them: a bake sees a surface's front, so a lightmap of an
outward floor would hold the world's light under it.
"""

import math
import sys

import bpy
from mathutils import Matrix

WHITE, RED, GREEN = (0.73, 0.73, 0.73), (0.65, 0.05, 0.05), (0.12, 0.45, 0.15)
WOOD = (0.45, 0.3, 0.18)
SKY = (0.35, 0.5, 0.8)
CORNELL_SIZE = 2.0
ROOM_X, ROOM_Y, ROOM_Z = 4.0, 4.0, 2.6
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

    def material(self, name, color):
        """A Principled BSDF at Blender's defaults (= shgi.Material's) with this base colour."""
        if name not in self.materials:
            material = bpy.data.materials.new(name)
            material.use_nodes = True
            principled = material.node_tree.nodes["Principled BSDF"]
            principled.inputs["Base Color"].default_value = (*color, 1.0)
            material.diffuse_color = (*color, 1.0)  # the Solid viewport colour
            self.materials[name] = material
        return self.materials[name]

    def part(self, name, geometry, material, color):
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


SCENES = {"cornell_box": cornell_box, "sun_room": sun_room}


def build(name, scale=1.0, lightmap=False):
    """Builds scene `name` ("cornell_box" or "sun_room") in a fresh file; returns the scene.
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
