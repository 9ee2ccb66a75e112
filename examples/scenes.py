"""The project's test and demo scenes, built from numpy arrays with the shgi scripting API.

Blender's frame: Z up, metres. Both scenes face the camera along +Y.

* cornell_box(): the classic box (2 m), white/red/green walls, two white blocks, a square area
  light just under the ceiling, front open towards the camera, black world.
* sun_room(): a closed 4 x 4 x 2.6 m room whose left wall has a 1.4 x 1.2 m window; the sun
  shines through it onto the floor, a blue sky fills the window; the camera stands inside.
* closed_room(): a closed box of one material (by default the furnace: every wall emits and
  reflects, so its exact light is the same everywhere), and room_wall_points() to sample it.
"""

import numpy as np

import shgi

WHITE, RED, GREEN = (0.73, 0.73, 0.73), (0.65, 0.05, 0.05), (0.12, 0.45, 0.15)
# Lightmap UVs of a quad's corners c, c + u, c + u + v, c + v.
UNIT_SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)


def quad(corner, edge_u, edge_v):
    """Vertices and triangles of the parallelogram corner + [0,1]u + [0,1]v (front: u x v)."""
    c, u, v = (np.asarray(x, np.float32) for x in (corner, edge_u, edge_v))
    return np.array([c, c + u, c + u + v, c + v], np.float32), np.array([[0, 1, 2], [0, 2, 3]])


def box(center, sx, sy, sz, angle):
    """A closed box (12 triangles, outward CCW) standing on z = center[2], turned about Z."""
    x, y = sx / 2, sy / 2
    corners = np.array([[-x, -y, 0], [x, -y, 0], [x, y, 0], [-x, y, 0],
                        [-x, -y, sz], [x, -y, sz], [x, y, sz], [-x, y, sz]], np.float32)
    c, s = np.cos(angle), np.sin(angle)
    corners = corners @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]], np.float32)
    corners += np.asarray(center, np.float32)
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    triangles = [[f[0], f[1], f[2]] for f in faces] + [[f[0], f[2], f[3]] for f in faces]
    return corners, np.array(triangles, np.int32)


def look_at(eye, target, up=(0, 0, 1)):
    """Blender-style camera matrix_world (row-major): looks down local -Z with +Y up."""
    eye, target, up = (np.asarray(v, np.float64) for v in (eye, target, up))
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1] = right, np.cross(right, forward)
    matrix[:3, 2], matrix[:3, 3] = -forward, eye
    return matrix


class SceneBuilder:
    """Adds named parts to a shgi.Scene, sharing one material per name."""

    def __init__(self, lightmap=False):
        self.scene = shgi.Scene()
        self.materials = {}
        self.lightmap = lightmap

    def material(self, name, color, **fields):
        if name not in self.materials:
            self.materials[name] = self.scene.add_material(
                shgi.Material(name=name, base_color=color, **fields))
        return self.materials[name]

    def part(self, name, geometry, material, color):
        """With `lightmap`, a quad (a wall) is turned to face the other way, into the room, and
        gets the UV map "LightmapUV" spanning the unit square: bakes see a surface's front."""
        positions, triangles = geometry
        uvs = None
        if self.lightmap and len(positions) == 4:
            uvs = {"LightmapUV": UNIT_SQUARE}
            triangles = triangles[:, ::-1]
        mesh_id = self.scene.add_mesh(
            positions=positions, triangles=triangles, name=name, uvs=uvs,
            material_indices=np.full(len(triangles), self.material(material, color)))
        return self.scene.add_instance(mesh_id, np.eye(4), name)

    def camera(self, eye, target, lens, width, height, scale):
        camera = shgi.Camera(lens=lens, resolution_x=max(1, round(width * scale)),
                             resolution_y=max(1, round(height * scale)))
        camera.world_from_camera = look_at(eye, target)
        self.scene.set_camera(camera)


def cornell_box(scale=1.0, lightmap=False):
    """256 x 256 pixels times `scale`. lightmap: walls face into the box, with LightmapUV."""
    b = SceneBuilder(lightmap)
    size = 2.0
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
    b.part("short_block", box((0.35, 0.7, 0.0), 0.6, 0.6, 0.6, np.radians(-18)), "white", WHITE)
    b.part("tall_block", box((-0.35, 1.3, 0.0), 0.6, 0.6, 1.2, np.radians(17)), "white", WHITE)
    light = shgi.Light(name="ceiling_light", type=shgi.LightType.AREA, power=60.0,
                       shape=shgi.AreaShape.SQUARE, size_x=0.5, size_y=0.5,
                       visible_camera=True)  # the classic box shows its light panel
    light.world_from_light = np.array([[1, 0, 0, 0], [0, 1, 0, 1.0], [0, 0, 1, size - 0.01],
                                       [0, 0, 0, 1]], np.float32)  # emits down its local -Z
    b.scene.add_light(light)
    b.scene.set_world(shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))
    b.camera(eye=(0, -3.6, 1.0), target=(0, 1.0, 1.0), lens=50.0, width=256, height=256,
             scale=scale)
    return b


def sun_room(scale=1.0, lightmap=False, window_shut=False):
    """256 x 192 pixels times `scale`. lightmap: walls face into the room, with LightmapUV.
    window_shut: a plaster quad over the window and the sky off (no light enters: light a
    method shows inside came through the walls)."""
    b = SceneBuilder(lightmap)
    room_x, room_y, room_z = 4.0, 4.0, 2.6
    x0, y0 = -room_x / 2, 0.0
    b.part("floor", quad((x0, y0, 0), (0, room_y, 0), (room_x, 0, 0)), "plaster", WHITE)
    b.part("ceiling", quad((x0, y0, room_z), (room_x, 0, 0), (0, room_y, 0)), "plaster", WHITE)
    b.part("back", quad((x0, room_y, 0), (0, 0, room_z), (room_x, 0, 0)), "plaster", WHITE)
    b.part("right", quad((-x0, y0, 0), (0, room_y, 0), (0, 0, room_z)), "plaster", WHITE)
    b.part("front", quad((x0, y0, 0), (room_x, 0, 0), (0, 0, room_z)), "plaster", WHITE)
    # Left wall (x = x0, facing +X) with a window from y 1.3..2.7, z 0.9..2.1, as four quads.
    win_y, win_z = (1.3, 2.7), (0.9, 2.1)
    left = [((x0, y0, 0), (0, 0, win_z[0]), (0, room_y, 0)),
            ((x0, y0, win_z[1]), (0, 0, room_z - win_z[1]), (0, room_y, 0)),
            ((x0, y0, win_z[0]), (0, 0, win_z[1] - win_z[0]), (0, win_y[0], 0)),
            ((x0, win_y[1], win_z[0]), (0, 0, win_z[1] - win_z[0]), (0, room_y - win_y[1], 0))]
    for i, (corner, u, v) in enumerate(left):
        b.part(f"left_wall_{i}", quad(corner, u, v), "plaster", WHITE)
    b.part("table", box((0.6, 2.2, 0.0), 1.0, 0.7, 0.75, np.radians(10)), "wood", (0.45, 0.3, 0.18))
    sun = shgi.Light(name="sun", type=shgi.LightType.SUN, strength=6.0, angle=np.radians(1.0))
    # Sun direction: from the upper left through the window, down onto the floor.
    b_dir = np.array([1.0, 0.15, -0.6])
    b_dir /= np.linalg.norm(b_dir)
    sun.world_from_light = look_at((0, 0, 0), b_dir).astype(np.float32)
    b.scene.add_light(sun)
    # A portal over the window (Cycles' area light Portal), facing into the room: sky light is
    # sampled through the opening instead of over the whole hemisphere.
    window_center = (x0, 0.5 * sum(win_y), 0.5 * sum(win_z))
    portal = shgi.Light(name="window_portal", type=shgi.LightType.AREA, portal=True,
                        shape=shgi.AreaShape.RECTANGLE, size_x=win_y[1] - win_y[0],
                        size_y=win_z[1] - win_z[0])
    portal.world_from_light = look_at(window_center, np.add(window_center, (1.0, 0.0, 0.0)))
    b.scene.add_light(portal)
    b.scene.set_world(shgi.World(color=(0.35, 0.5, 0.8), strength=0.0 if window_shut else 1.0))
    if window_shut:
        b.part("shutter", quad((x0, win_y[0], win_z[0]), (0, 0, win_z[1] - win_z[0]),
                               (0, win_y[1] - win_y[0], 0)), "plaster", WHITE)
    b.camera(eye=(1.7, 0.25, 1.5), target=(-0.8, 2.6, 0.8), lens=16.0, width=256, height=192,
             scale=scale)
    return b


def two_rooms(scale=1.0, bright_power=2000.0, dim_power=20.0):
    """Two closed rooms side by side, split by a solid wall 0.1 m thick: the left room lit by a
    bright lamp, the right one by a dim lamp. The camera stands in the dim room facing the wall.
    The leak test of probe grids (docs/methods.md): light must not cross the wall.
    128 x 96 px x scale. The lamps' powers (W) can be changed (0 turns one off) to tell the
    light that crosses the wall from the dim room's own."""
    b = SceneBuilder()
    sx, sy, sz = 6.0, 3.0, 2.5  # the shell spans x in [-3, 3]
    shell = [  # six faces of the shell, facing in
        ("floor", (-3, 0, 0), (0, sy, 0), (sx, 0, 0)),
        ("ceiling", (-3, 0, sz), (sx, 0, 0), (0, sy, 0)),
        ("front", (-3, 0, 0), (sx, 0, 0), (0, 0, sz)),
        ("back", (-3, sy, 0), (0, 0, sz), (sx, 0, 0)),
        ("left", (-3, 0, 0), (0, 0, sz), (0, sy, 0)),
        ("right", (3, 0, 0), (0, sy, 0), (0, 0, sz)),
    ]
    for name, corner, u, v in shell:
        b.part(name, quad(corner, u, v), "plaster", WHITE)
    b.part("wall", box((0.0, sy / 2, 0.0), 0.1, sy, sz, 0.0), "plaster", WHITE)
    for name, x, power in [("bright_lamp", -1.5, bright_power), ("dim_lamp", 1.5, dim_power)]:
        lamp = shgi.Light(name=name, type=shgi.LightType.POINT, power=power, radius=0.05)
        lamp.world_from_light = np.array([[1, 0, 0, x], [0, 1, 0, sy / 2], [0, 0, 1, 2.0],
                                          [0, 0, 0, 1]], np.float32)
        b.scene.add_light(lamp)
    b.scene.set_world(shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))
    b.camera(eye=(2.9, 0.2, 1.4), target=(0.0, 2.2, 1.0), lens=18.0, width=128, height=96,
             scale=scale)
    return b


def hall(scale=1.0):
    """A hall 32 x 8 x 4 m (x in [-16, 16]), open at both ends, white floor and ceiling, red and
    green long walls, three white blocks, four 1 m area lamps under the ceiling along it; the
    camera stands at x = -4 looking across. Larger than one 32-cell light propagation volume
    resolves (1 m cells): the cascades' test and bench scene. 96 x 64 px x scale."""
    b = SceneBuilder()
    b.part("floor", quad((-16, -4, 0), (32, 0, 0), (0, 8, 0)), "white", WHITE)
    b.part("ceiling", quad((-16, -4, 4), (0, 8, 0), (32, 0, 0)), "white", WHITE)
    b.part("north", quad((-16, 4, 0), (0, 0, 4), (32, 0, 0)), "red", RED)
    b.part("south", quad((-16, -4, 0), (32, 0, 0), (0, 0, 4)), "green", GREEN)
    for i, (x, y) in enumerate([(-6, 1), (2, -1.5), (10, 2)]):
        b.part(f"block{i}", box((x, y, 0), 1.0, 1.0, 1.5, 0.3), "white", WHITE)
    for i, x in enumerate([-12, -4, 4, 12]):
        lamp = shgi.Light(name=f"lamp{i}", type=shgi.LightType.AREA, power=200.0,
                          shape=shgi.AreaShape.SQUARE, size_x=1.0, size_y=1.0)
        lamp.world_from_light = np.array([[1, 0, 0, x], [0, 1, 0, 0], [0, 0, 1, 3.99],
                                          [0, 0, 0, 1]], np.float32)  # emits down its -Z
        b.scene.add_light(lamp)
    b.scene.set_world(shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))
    b.camera(eye=(-4, -3.5, 1.5), target=(-4, 2.0, 1.0), lens=18.0, width=96, height=64,
             scale=scale)
    return b


def closed_room(size=(3.0, 3.0, 2.5), material=None, lamp_at=None):
    """A closed box [0, size] seen from inside, all six walls of one shgi.Material (default: the
    furnace's, Lambert albedo 0.5 emitting radiance 1, so every wall point's irradiance is pi and
    the indirect part pi (a + ... + a^n) after n bounces), black world; with `lamp_at` a 100 W
    point lamp there. Without a camera: sample its walls with room_wall_points(). The default
    size is the two rooms' dim room alone (16 cells of a 32-cell volume of the two rooms)."""
    if material is None:
        material = shgi.Material(name="walls", base_color=(0.5, 0.5, 0.5),
                                 diffuse_model=shgi.DiffuseModel.LAMBERT, specular=0.0,
                                 emission_color=(1.0, 1.0, 1.0), emission_strength=1.0)
    sx, sy, sz = size
    b = SceneBuilder()
    b.materials[material.name] = b.scene.add_material(material)
    for name, corner, u, v in [
            ("floor", (0, 0, 0), (0, sy, 0), (sx, 0, 0)),
            ("ceiling", (0, 0, sz), (sx, 0, 0), (0, sy, 0)),
            ("front", (0, 0, 0), (sx, 0, 0), (0, 0, sz)),
            ("back", (0, sy, 0), (0, 0, sz), (sx, 0, 0)),
            ("left", (0, 0, 0), (0, 0, sz), (0, sy, 0)),
            ("right", (sx, 0, 0), (0, sy, 0), (0, 0, sz))]:
        b.part(name, quad(corner, u, v), material.name, material.base_color)
    if lamp_at is not None:
        lamp = shgi.Light(name="lamp", type=shgi.LightType.POINT, power=100.0, radius=0.05)
        lamp.world_from_light = np.array([[1, 0, 0, lamp_at[0]], [0, 1, 0, lamp_at[1]],
                                          [0, 0, 1, lamp_at[2]], [0, 0, 0, 1]], np.float32)
        b.scene.add_light(lamp)
    b.scene.set_world(shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))
    return b


def room_wall_points(size=(3.0, 3.0, 2.5), per_metre=16):
    """A grid over the six inner walls of closed_room(size): points (N, 3) and normals (N, 3)
    into the room (float32), each point's area (m^2) and its distance (m) to the nearest edge
    of its wall."""
    size = np.asarray(size, np.float64)
    points, normals, areas, edges = [], [], [], []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        nu, nv = (max(2, int(round(size[a] * per_metre))) for a in (u, v))
        gu, gv = np.meshgrid((np.arange(nu) + 0.5) / nu * size[u],
                             (np.arange(nv) + 0.5) / nv * size[v], indexing="ij")
        edge = np.minimum(np.minimum(gu, size[u] - gu), np.minimum(gv, size[v] - gv)).ravel()
        for side in (0, 1):
            p = np.zeros((gu.size, 3))
            p[:, u], p[:, v], p[:, axis] = gu.ravel(), gv.ravel(), side * size[axis]
            n = np.zeros((gu.size, 3))
            n[:, axis] = 1.0 if side == 0 else -1.0
            points.append(p)
            normals.append(n)
            areas.append(np.full(gu.size, size[u] * size[v] / gu.size))
            edges.append(edge)
    return (np.concatenate(points).astype(np.float32), np.concatenate(normals).astype(np.float32),
            np.concatenate(areas), np.concatenate(edges))
