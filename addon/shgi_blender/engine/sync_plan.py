"""What a viewport sync must export again, from the depsgraph's updates. No bpy.

Blender reports each edit as ``depsgraph.updates``: the IDs it re-evaluated with three flags
(is_updated_geometry, is_updated_transform, is_updated_shading). viewport_sync.py turns each
into an UpdateRecord (plain values) and ``plan_updates`` decides which caches of the
IncrementalExport to drop. What Blender sends, measured on Blender 3.4:

=============================  =========================================================
edit                           updates
=============================  =========================================================
move an object                 Object (transform)
edit a mesh                    Object (geometry, shading), Mesh (all three)
edit a material's nodes        Material (shading), its embedded ShaderNodeTree
another material in a slot     Object and Mesh (all three), the Material (shading)
change a light's power         light Object (geometry), Light data (all three)
edit the world                 World (shading), its embedded ShaderNodeTree
=============================  =========================================================

Geometry is dropped only for objects and meshes flagged geometry (a light object flagged
geometry is a light edit: lights are read again at every sync anyway). A node group (a
ShaderNodeTree that is not embedded in a material or world) may feed any material, so its edit
drops every material and the world; an image edit drops every material (textures) and the
world (environment average). Another world assigned to the scene is seen by the sync itself.
"""

from dataclasses import dataclass, field

# Object types whose geometry is exported (export/scene_export.MESH_CONVERTIBLE_TYPES).
GEOMETRY_OBJECT_TYPES = ("MESH", "CURVE", "SURFACE", "FONT", "META")


@dataclass(frozen=True)
class UpdateRecord:
    """One depsgraph update as plain values.

    kind: "OBJECT", "MESH", "MATERIAL", "WORLD", "IMAGE", "NODETREE", "LIGHT", "SCENE",
    "COLLECTION" or "OTHER"; name: the original ID's name_full; object_type and data_name: an
    object's type and its data's name_full (objects only); embedded: a node tree owned by a
    material or world.
    """

    kind: str
    name: str
    geometry: bool = False
    transform: bool = False
    shading: bool = False
    object_type: str = ""
    data_name: str = ""
    embedded: bool = False


@dataclass
class SyncPlan:
    """The caches to drop before exporting again (see the module docstring)."""

    full: bool = False                                 # drop everything (first sync)
    geometry_names: set = field(default_factory=set)   # objects and mesh data (name_full)
    material_names: set = field(default_factory=set)
    all_materials: bool = False
    world: bool = False

    @property
    def geometry(self):
        return self.full or bool(self.geometry_names)


def plan_updates(records):
    """The SyncPlan of a sequence of UpdateRecords."""
    plan = SyncPlan()
    for record in records:
        if record.kind == "OBJECT":
            if record.geometry and record.object_type in GEOMETRY_OBJECT_TYPES:
                plan.geometry_names.add(record.name)
                if record.data_name:
                    plan.geometry_names.add(record.data_name)
        elif record.kind == "MESH":
            if record.geometry:
                plan.geometry_names.add(record.name)
        elif record.kind == "MATERIAL":
            plan.material_names.add(record.name)
        elif record.kind == "NODETREE":
            if not record.embedded:
                plan.all_materials = plan.world = True
        elif record.kind == "IMAGE":
            plan.all_materials = plan.world = True
        elif record.kind == "WORLD":
            plan.world = True
    return plan


def full_plan():
    return SyncPlan(full=True, all_materials=True, world=True)
