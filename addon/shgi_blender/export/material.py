"""Blender materials and images → shgi.Material and shgi.Texture (bpy side).

Reads the node feeding the active Material Output's Surface input (through the Mix Shader of a
lightmap preview, bake_settings.LIGHTMAP_MIX_NODE): a Principled BSDF, an Emission shader or a
Diffuse BSDF. Socket names and units are mapped in conversions.py. An Image Texture node linked
to the Principled Base Color becomes an shgi.Texture with base_color = 1 (SHGI multiplies
texture × base_color). A Normal Map node on the Principled Normal input, fed by an Image Texture,
becomes the material's normal map (tangent, object or world space, with its Strength); the
meshes using it then export tangents of the node's UV map (MeshExporter asks
tangent_uv_map()). Anything else gets the documented fallback material
(conversions.fallback_material_fields) and a warning naming the material, and so does an input
holding NaN or an infinity; an emission brighter than SHGI renders (conversions.MAX_EMISSION) is
turned off with a warning. Image pixels that are NaN or infinite are read as 0, with a warning
naming the image.
"""

import bpy
import numpy as np
import shgi

from ..bake_settings import LIGHTMAP_MIX_NODE
from . import conversions, node_tree

MATERIAL_OUTPUT_NODE = "ShaderNodeOutputMaterial"
IMAGE_TEXTURE_NODE = "ShaderNodeTexImage"
UV_MAP_NODE = "ShaderNodeUVMap"
NORMAL_MAP_NODE = "ShaderNodeNormalMap"
BUMP_NODE = "ShaderNodeBump"
# The Normal Map node's spaces, as shgi.NormalMapSpace names them (all of them: Blender's own
# object and world spaces negate the texel's Y and Z).
NORMAL_MAP_SPACES = {name: name for name in ("TANGENT", "OBJECT", "WORLD", "BLENDER_OBJECT",
                                             "BLENDER_WORLD")}
# The name of the one material shared by every surface without a usable material.
FALLBACK_MATERIAL_NAME = "SHGI fallback"
RGB_CHANNELS = 3


class MaterialExporter:
    """Adds each Blender material (and image) once to an shgi.Scene and remembers its id."""

    def __init__(self, scene, log):
        """scene: an shgi.Scene, or anything with add_material and add_texture (and, for
        invalidate(), set_material and set_texture: export/scene_snapshot.MaterialTable)."""
        self._scene = scene
        self._log = log
        self._material_ids = {}
        self._texture_ids = {}
        self._fallback_id = None
        self._stale = set()  # material and image keys to convert again, in place
        self.conversions = 0  # materials converted so far (the viewport's sync counts them)
        # Scene material id → the UV map whose tangents its tangent-space normal map reads
        # ('' = the render UV map).
        self._tangent_uv_maps = {}

    @property
    def texture_count(self):
        """Number of textures added."""
        return sum(1 for texture_id in self._texture_ids.values() if texture_id is not None)

    def fallback_id(self):
        """Id of the shared fallback material (added on first use)."""
        if self._fallback_id is None:
            fields = conversions.fallback_material_fields()
            self._fallback_id = self._scene.add_material(
                shgi.Material(name=FALLBACK_MATERIAL_NAME, **fields))
        return self._fallback_id

    def slot_ids(self, obj):
        """Scene material ids of an object's material slots (fallback for empty slots)."""
        if not obj.material_slots:
            self._log.warn(f"object {obj.name!r} has no material; using the fallback "
                           f"(grey {conversions.FALLBACK_BASE_COLOR[0]}, roughness "
                           f"{conversions.FALLBACK_ROUGHNESS})")
            return [self.fallback_id()]
        ids = []
        for index, slot in enumerate(obj.material_slots):
            if slot.material is None:
                self._log.warn(f"object {obj.name!r}: material slot {index} is empty; "
                               "using the fallback material")
                ids.append(self.fallback_id())
            else:
                ids.append(self.material_id(slot.material))
        return ids

    def tangent_uv_map(self, material_ids):
        """The UV map whose tangents the first of these materials with a tangent-space normal
        map needs ('' = the render UV map), or None when none has one."""
        for material_id in material_ids:
            if material_id in self._tangent_uv_maps:
                return self._tangent_uv_maps[material_id]
        return None

    def invalidate(self, material_keys=None):
        """Marks materials (by ``original.name_full``; None: all materials and images) to be
        converted again on their next use, keeping their ids (the viewport's edits)."""
        if material_keys is None:
            self._stale.update(("MATERIAL", key) for key in self._material_ids)
            self._stale.update(("IMAGE", key) for key in self._texture_ids)
        else:
            self._stale.update(("MATERIAL", key) for key in material_keys)

    def material_id(self, material):
        """Scene id of a Blender material, converting it on first use; a stale material is
        converted again in place, at the id it has, so the meshes using that id see the edit."""
        key = material.original.name_full
        if key in self._material_ids and ("MATERIAL", key) not in self._stale:
            return self._material_ids[key]
        self._stale.discard(("MATERIAL", key))
        self.conversions += 1
        converted = self._convert(material)
        own_id = self._material_ids.get(key)  # set only for a stale material
        if own_id is not None and own_id != self._fallback_id:
            if converted is None:
                converted = self._scene.materials[self.fallback_id()]
            self._scene.set_material(own_id, converted)
        elif converted is None:
            self._material_ids[key] = self.fallback_id()
        else:
            self._material_ids[key] = self._scene.add_material(converted)
        material_id = self._material_ids[key]
        self._tangent_uv_maps.pop(material_id, None)
        if (converted is not None and converted.normal_texture >= 0
                and converted.normal_space == shgi.NormalMapSpace.TANGENT):
            self._tangent_uv_maps[material_id] = converted.normal_uv_set
        return material_id

    def _convert(self, material):
        """shgi.Material of a Blender material, or None (after a warning) for the fallback."""
        surface, problem = _surface_node(material)
        if surface is None:
            self._log.warn(f"material {material.name!r} {problem}; using the fallback material")
            return None
        fields = self._surface_fields(material, surface)
        if fields is None:
            return None
        names = conversions.input_names(surface.bl_idname, bpy.app.version)
        bad = conversions.non_finite_fields(fields)
        if bad:
            inputs = ", ".join(f"{names.get(name, name)} {fields[name]}" for name in bad)
            verb = "is not a finite number" if len(bad) == 1 else "are not finite numbers"
            self._log.warn(f"material {material.name!r}: {inputs} {verb} (NaN or infinite); "
                           "using the fallback material")
            return None
        self._check_emission(material, fields, names)
        clamped, changed = conversions.clamp_material_fields(fields)
        if changed:
            self._log.warn(f"material {material.name!r}: {', '.join(changed)} clamped to the "
                           "range SHGI accepts")
        return shgi.Material(name=material.name, **clamped)

    def _check_emission(self, material, fields, names):
        """Turns off (after a warning) an emission brighter than SHGI renders."""
        if "emission_strength" not in fields:
            return
        quantity = f"{names['emission_color']} × {names['emission_strength']}"
        problem = conversions.emission_problem(fields["emission_color"],
                                               fields["emission_strength"], quantity,
                                               conversions.RADIANCE_UNIT)
        if problem is not None:
            self._log.warn(f"material {material.name!r}: {problem}; its emission is turned off: "
                           f"lower {names['emission_strength']}")
            fields["emission_strength"] = 0.0

    def _surface_fields(self, material, surface):
        """shgi.Material fields of a material's surface shader node, or None (after a warning)
        for the fallback."""
        values = node_tree.input_values(surface)
        if surface.bl_idname == conversions.PRINCIPLED_NODE:
            return self._principled_fields(material, surface, values)
        self._warn_linked_inputs(material, surface, ())
        if surface.bl_idname == conversions.EMISSION_NODE:
            return conversions.material_fields_from_emission(values["Color"], values["Strength"])
        if surface.bl_idname == conversions.DIFFUSE_NODE:
            return conversions.material_fields_from_diffuse(values["Color"])
        self._log.warn(f"material {material.name!r}: surface shader {surface.bl_idname} is not "
                       "supported (Principled BSDF, Emission, Diffuse BSDF are); using the "
                       "fallback material")
        return None

    def _principled_fields(self, material, node, values):
        """Fields of a Principled BSDF, with an Image Texture on Base Color as a texture."""
        distribution = getattr(node, "distribution", conversions.DEFAULT_PRINCIPLED_DISTRIBUTION)
        if distribution not in conversions.PRINCIPLED_DISTRIBUTIONS:
            self._log.warn(f"material {material.name!r}: distribution {distribution!r} is not "
                           "rendered by SHGI; using GGX")
            distribution = "GGX"
        fields = conversions.material_fields_from_principled(values, bpy.app.version,
                                                             distribution)
        ignored = conversions.ignored_principled_inputs(values)
        if ignored:
            self._log.warn(f"material {material.name!r}: Principled inputs {', '.join(ignored)} "
                           "are not rendered by SHGI and were ignored")
        base_socket = conversions.principled_socket_names(bpy.app.version)["base_color"]
        texture_node = node_tree.linked_node(node.inputs[base_socket])
        handled = ()
        if texture_node is not None and texture_node.bl_idname == IMAGE_TEXTURE_NODE:
            texture_id = self._texture_id(texture_node.image, material.name)
            if texture_id is not None:
                fields.update(base_color=(1.0, 1.0, 1.0), base_color_texture=texture_id,
                              base_color_uv_set=_uv_map_name(texture_node))
                handled = (base_socket,)
        if self._normal_fields(material, node, fields):
            handled += ("Normal",)
        self._warn_linked_inputs(material, node, handled)
        return fields

    def _normal_fields(self, material, node, fields):
        """Adds what drives the shader's Normal input to `fields`: a Normal Map node, or a Bump
        node (with a Normal Map node on its own Normal input, or none); True when it is one of
        those (handled, or ignored with a warning)."""
        if "Normal" not in node.inputs:
            return False
        source = node_tree.linked_node(node.inputs["Normal"])
        if source is None:
            return False
        if source.bl_idname == NORMAL_MAP_NODE:
            self._normal_map_fields(material, source, fields)
            return True
        if source.bl_idname != BUMP_NODE:
            return False
        self._bump_fields(material, source, fields)
        below = node_tree.linked_node(source.inputs["Normal"])
        if below is not None and below.bl_idname == NORMAL_MAP_NODE:
            self._normal_map_fields(material, below, fields)
        elif below is not None:
            self._log.warn(f"material {material.name!r}: the Bump node's Normal is driven by a "
                           f"{below.bl_idname} node that SHGI does not evaluate; the bump is "
                           "applied to the interpolated normal")
        return True

    def _bump_fields(self, material, bump, fields):
        """Adds a Bump node whose Height is an Image Texture's Color to `fields` (else warns
        and leaves it out)."""
        height = node_tree.linked_output(bump.inputs["Height"])
        if height is None:
            return  # an unlinked Height is a constant: no bumps
        texture_node = height.node
        if texture_node.bl_idname != IMAGE_TEXTURE_NODE or height.name != "Color":
            self._log.warn(f"material {material.name!r}: the Bump node's Height is not an Image "
                           "Texture's Color; the bump is ignored")
            return
        texture_id = self._texture_id(texture_node.image, material.name)
        if texture_id is None:
            return
        for name in ("Strength", "Distance", "Filter Width"):
            if name in bump.inputs and bump.inputs[name].is_linked:
                self._log.warn(f"material {material.name!r}: the Bump node's {name} is driven "
                               "by a node SHGI does not evaluate; its unlinked value is used")
        distance = float(bump.inputs["Distance"].default_value)
        fields.update(bump_texture=texture_id, bump_uv_set=_uv_map_name(texture_node),
                      bump_strength=min(max(float(bump.inputs["Strength"].default_value), 0.0),
                                        1.0),
                      bump_distance=-distance if bump.invert else distance)

    def _normal_map_fields(self, material, normal_map, fields):
        """Adds the normal map of a Normal Map node (fed by an Image Texture) to `fields`."""
        space = NORMAL_MAP_SPACES.get(normal_map.space)
        if space is None:
            self._log.warn(f"material {material.name!r}: Normal Map space {normal_map.space!r} "
                           "is not one SHGI knows; the normal map is ignored")
            return
        texture_node = node_tree.linked_node(normal_map.inputs["Color"])
        if texture_node is None or texture_node.bl_idname != IMAGE_TEXTURE_NODE:
            self._log.warn(f"material {material.name!r}: the Normal Map node's Color is not an "
                           "Image Texture; the normal map is ignored")
            return
        image = texture_node.image
        if image is not None and conversions.texture_needs_srgb_decode(
                image.colorspace_settings.name, image.is_float):
            # Decoded as Cycles decodes it, so both render the same (bent) normals.
            self._log.warn(f"material {material.name!r}: normal map image {image.name!r} is in "
                           f"colour space {image.colorspace_settings.name!r}; normal maps are "
                           "non-colour data (set the image's Color Space to Non-Color)")
        texture_id = self._texture_id(texture_node.image, material.name)
        if texture_id is None:
            return
        strength_socket = normal_map.inputs["Strength"]
        if strength_socket.is_linked:
            self._log.warn(f"material {material.name!r}: the Normal Map's Strength is driven by "
                           "a node SHGI does not evaluate; its unlinked value is used")
        uv_map = normal_map.uv_map if space == "TANGENT" else _uv_map_name(texture_node)
        fields.update(normal_texture=texture_id, normal_uv_set=uv_map,
                      normal_strength=float(strength_socket.default_value),
                      normal_space=getattr(shgi.NormalMapSpace, space))

    def _warn_linked_inputs(self, material, node, handled):
        """Warns about linked inputs whose unlinked value is used instead."""
        for socket in node.inputs:
            if socket.is_linked and socket.name not in handled and hasattr(socket, "default_value"):
                source = node_tree.linked_node(socket)
                if source is None:
                    continue
                self._log.warn(f"material {material.name!r}: input {socket.name!r} is driven by "
                               f"a {source.bl_idname} node that SHGI does not evaluate; its "
                               "unlinked value is used")

    def _texture_id(self, image, material_name):
        """Scene id of an image as a linear texture, or None (after a warning)."""
        if image is None:
            self._log.warn(f"material {material_name!r}: Image Texture node has no image")
            return None
        key = image.name_full
        if key not in self._texture_ids:
            self._texture_ids[key] = self._add_texture(image, material_name)
        elif ("IMAGE", key) in self._stale:
            self._stale.discard(("IMAGE", key))
            texture = self._read_texture(image, material_name)
            if texture is not None and self._texture_ids[key] is not None:
                self._scene.set_texture(self._texture_ids[key], texture)
            elif texture is not None:
                self._texture_ids[key] = self._scene.add_texture(texture)
        return self._texture_ids[key]

    def _add_texture(self, image, material_name):
        texture = self._read_texture(image, material_name)
        return None if texture is None else self._scene.add_texture(texture)

    def _read_texture(self, image, material_name):
        """The image as an shgi.Texture, or None (after a warning) when it has no pixels."""
        width, height = image.size
        if width == 0 or height == 0 or image.channels == 0:
            self._log.warn(f"material {material_name!r}: image {image.name!r} has no pixels "
                           "(missing file?); base colour untextured")
            return None
        return shgi.Texture(image_pixels(image, self._log), name=image.name)


def image_pixels(image, log):
    """(H, W, C) float32 linear pixels of a Blender image, row 0 at the bottom; NaN and infinite
    values become 0 (black), with a warning naming the image."""
    width, height = image.size
    pixels = np.empty(width * height * image.channels, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, image.channels)
    bad = ~np.isfinite(pixels)
    if bad.any():
        log.warn(f"image {image.name!r}: {int(bad.sum())} of its {bad.size} pixel values are NaN "
                 "or infinite; SHGI reads them as 0 (black): fix or replace the image")
        pixels[bad] = 0.0
    colorspace = image.colorspace_settings.name
    if not conversions.texture_colorspace_is_known(colorspace):
        log.warn(f"image {image.name!r}: colour space {colorspace!r} is not supported; its "
                 "values are used as linear")
    if conversions.texture_needs_srgb_decode(colorspace, image.is_float):
        rgb = min(RGB_CHANNELS, image.channels)
        pixels[:, :, :rgb] = shgi.linear_from_srgb(np.ascontiguousarray(pixels[:, :, :rgb]))
    return pixels


def _surface_node(material):
    """(node feeding the active Material Output's Surface, None) or (None, what is wrong)."""
    if not material.use_nodes or material.node_tree is None:
        return None, "does not use nodes"
    output = node_tree.active_output(material.node_tree, MATERIAL_OUTPUT_NODE)
    if output is None:
        return None, "has no Material Output node"
    surface = node_tree.linked_node(output.inputs["Surface"])
    if surface is not None and surface.name == LIGHTMAP_MIX_NODE:
        surface = node_tree.linked_node(surface.inputs[1])
    if surface is None:
        return None, "has nothing connected to the Material Output's Surface"
    return surface, None


def _uv_map_name(texture_node):
    """The UV map an Image Texture reads: a UV Map node's map, else '' (the render UV map)."""
    source = node_tree.linked_node(texture_node.inputs["Vector"])
    if source is not None and source.bl_idname == UV_MAP_NODE:
        return source.uv_map
    return ""
