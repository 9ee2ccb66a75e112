"""Blender data → SHGI field values, without bpy (pytest checks every rule outside Blender).

The bpy side (material.py, light.py, camera.py) reads plain values out of Blender — socket
default values by socket name, light and camera properties — and this module turns them into
keyword arguments for ``shgi.Material``, ``shgi.Light``, ``shgi.Camera`` and ``shgi.World``.
Everything that depends on Blender's version or units lives here.

Principled BSDF socket names (``principled_socket_names``):

=================  ====================  ======================
SHGI field         Blender 3.x           Blender 4.x
=================  ====================  ======================
base_color         "Base Color"          "Base Color"
metallic           "Metallic"            "Metallic"
roughness          "Roughness"           "Roughness"
ior                "IOR"                 "IOR"
specular           "Specular"            "Specular IOR Level"
transmission       "Transmission"        "Transmission Weight"
emission_color     "Emission"            "Emission Color"
emission_strength  "Emission Strength"   "Emission Strength"
=================  ====================  ======================

Units: SHGI's material is Blender 3.4's Principled (dielectric F0 = 0.08 · specular). Blender 4's
"Specular IOR Level" scales the Fresnel reflectance given by the IOR, as Cycles 4 does:
F0 = ((ior − 1) / (ior + 1))² · 2 · level (0.5 = the IOR's own reflectance), so
specular = F0 / 0.08. Blender 4's Principled diffuse is Lambertian (3.4's is Burley's, with
roughness retro-reflection): from 4.0 it exports as ``diffuse_model`` LAMBERT. From 4.0 Cycles
also layers the specular over the diffuse ("Principled v2": ``principled_model`` V2, which dims the
diffuse by the specular's albedo and fills Glossy Color with it), with the node's distribution
(Blender 4's default "Multiscatter GGX" → ``distribution`` MULTISCATTER_GGX). Lights: point,
spot and area "Power" in W → ``power``; the sun's "Strength" in W/m² → ``strength`` (both are
Blender's ``Light.energy``); angles in radians as Blender stores them. SHGI's lights are Blender
3.4's; Blender 4.0 changed one unit, the area light's radiance L = P / (4 A) to L = P / (π A)
(blender/blender issue 109404), so from 4.0 an area light's power is exported × 4 / π; and 4.0
dropped the cos(angle to the axis) that 3.4 multiplies a spot's falloff by (``spot_cone_cosine``
False from 4.0). Matrices
are Blender's ``matrix_world`` as row-major 4 × 4 numpy arrays.
"""

import math

import numpy as np
import shgi

# Blender 4.0 renamed the Principled BSDF's inputs and made its diffuse Lambertian ("Principled
# v2").
PRINCIPLED_V2_VERSION = (4, 0, 0)
# The Blender whose light units SHGI's native lights use (native/render/light_sampler.h).
NATIVE_LIGHT_UNITS_VERSION = (3, 4, 1)
# Blender 4.0 made an area light of power P a Lambertian emitter of radiance P / (π A); Blender
# 3.4's (and SHGI's) is P / (4 A). Measured: on-axis irradiance under a 5 cm square light at 2 m
# is 0.785 · P / (π d²) in Blender 3.4.1 and 1.000 · P / (π d²) in Blender 5.0.1.
AREA_LIGHT_PI_VERSION = (4, 0, 0)
AREA_POWER_TO_NATIVE_FROM_4_0 = 4.0 / math.pi
# Blender 4.0's Cycles attenuates a spot light by the smoothstep of its blend only; 3.4's also by
# cos(angle to the spot's axis) (intern/cycles/kernel/light/spot.h).
SPOT_WITHOUT_CONE_COSINE_VERSION = (4, 0, 0)
# Blender 4's Principled BSDF distributions → shgi.MicrofacetDistribution ("Multiscatter GGX" is
# the default). Blender 3.x's distribution is not exported: SHGI renders its Principled as GGX.
PRINCIPLED_DISTRIBUTIONS = {"GGX": shgi.MicrofacetDistribution.GGX,
                            "MULTI_GGX": shgi.MicrofacetDistribution.MULTISCATTER_GGX}
DEFAULT_PRINCIPLED_DISTRIBUTION = "MULTI_GGX"

_PRINCIPLED_SOCKETS_3X = {
    "base_color": "Base Color",
    "metallic": "Metallic",
    "roughness": "Roughness",
    "ior": "IOR",
    "specular": "Specular",
    "transmission": "Transmission",
    "emission_color": "Emission",
    "emission_strength": "Emission Strength",
}
_PRINCIPLED_SOCKETS_4X = dict(
    _PRINCIPLED_SOCKETS_3X,
    specular="Specular IOR Level",
    transmission="Transmission Weight",
    emission_color="Emission Color",
)

# Blender 3.4's Principled BSDF: dielectric F0 = SPECULAR_F0_SCALE * specular
# (intern/cycles/kernel/closure/bsdf_principled_*: "0.08 * specular").
SPECULAR_F0_SCALE = 0.08
# Blender 4's "Specular IOR Level" at which the IOR's own reflectance is used unchanged.
NEUTRAL_SPECULAR_IOR_LEVEL = 0.5

# What Blender renders a surface without a usable material with: the Principled defaults
# (grey 0.8, roughness 0.5), as Cycles' default surface shader and Blender's "Material" do.
FALLBACK_BASE_COLOR = (0.8, 0.8, 0.8)
FALLBACK_ROUGHNESS = 0.5

# Cycles treats an IOR below 1 as 1 for the Principled BSDF's dielectric layer.
MIN_IOR = 1.0

# The shader node types the exporter understands at the Material Output's Surface input.
PRINCIPLED_NODE = "ShaderNodeBsdfPrincipled"
EMISSION_NODE = "ShaderNodeEmission"
DIFFUSE_NODE = "ShaderNodeBsdfDiffuse"

# Blender enum identifiers → shgi enums.
LIGHT_TYPES = {"POINT": shgi.LightType.POINT, "SPOT": shgi.LightType.SPOT,
               "SUN": shgi.LightType.SUN, "AREA": shgi.LightType.AREA}
AREA_SHAPES = {"SQUARE": shgi.AreaShape.SQUARE, "RECTANGLE": shgi.AreaShape.RECTANGLE,
               "DISK": shgi.AreaShape.DISK, "ELLIPSE": shgi.AreaShape.ELLIPSE}
CAMERA_TYPES = {"PERSP": shgi.CameraType.PERSPECTIVE, "ORTHO": shgi.CameraType.ORTHOGRAPHIC}
SENSOR_FITS = {"AUTO": shgi.SensorFit.AUTO, "HORIZONTAL": shgi.SensorFit.HORIZONTAL,
               "VERTICAL": shgi.SensorFit.VERTICAL}
# Blender's area shapes whose second side is size_y; the others are square / round.
AREA_SHAPES_WITH_SIZE_Y = ("RECTANGLE", "ELLIPSE")

# Image colour spaces whose byte pixels hold sRGB-encoded values that must be decoded.
SRGB_COLORSPACES = ("sRGB",)
# Colour spaces whose pixels are used as they are (already linear or data).
LINEAR_COLORSPACES = ("Linear", "Linear Rec.709", "Non-Color", "Raw", "Linear CIE-XYZ E",
                      "Linear FilmLight E-Gamut", "Rec.709 Linear")


# The brightest emitter SHGI is given, in the emitter's unit (a light's Power in W, a sun's
# Strength in W/m², an emission's or the world's radiance in W/m²/sr), times its colour's largest
# component. The native code keeps light in 32-bit floats (at most 3.4e38) and multiplies an
# emitter's emission by its area (for a sun or the world, the scene's bounding disk: 4π² r² for
# the world) before it sums the emitters, so Blender's largest values overflow to infinity. 1e20
# keeps a scene 1000 km across five orders of magnitude below that limit, and lies far beyond
# any real source (the Sun's disk is about 2e7 W/m²/sr).
MAX_EMISSION = 1e20
# Units of the emitters' values, for messages.
POWER_UNIT, IRRADIANCE_UNIT, RADIANCE_UNIT = "W", "W/m²", "W/m²/sr"


def emission_problem(color, strength, quantity, unit):
    """Why an emitter of colour × strength cannot be rendered, or None.

    quantity: what the artist sets, for the message ("Power × Color"); unit: its unit.
    """
    values = (*rgb(color), float(strength))
    if not all(math.isfinite(value) for value in values):
        return (f"{quantity} is {rgb(color)} × {float(strength)}, not finite numbers (NaN or "
                "infinite)")
    emission = max(values[:3]) * values[3]
    if emission > MAX_EMISSION:
        return (f"{quantity} is {emission:.3g} {unit}, above the {MAX_EMISSION:.0e} {unit} SHGI "
                "renders (its emitted power would overflow)")
    return None


def non_finite_fields(fields):
    """Names of the number and colour fields in `fields` that hold NaN or an infinity."""
    bad = []
    for name, value in fields.items():
        values = value if isinstance(value, tuple) else (value,)
        if any(isinstance(v, float) and not math.isfinite(v) for v in values):
            bad.append(name)
    return bad


def input_names(node_type, blender_version):
    """{shgi.Material field: the input of a shader node of `node_type` it comes from}, for
    messages naming what the artist set."""
    if node_type == PRINCIPLED_NODE:
        return principled_socket_names(blender_version)
    if node_type == EMISSION_NODE:
        return {"emission_color": "Color", "emission_strength": "Strength"}
    if node_type == DIFFUSE_NODE:
        return {"base_color": "Color"}
    return {}


def principled_socket_names(blender_version):
    """{shgi field: Principled BSDF input name} for a Blender version tuple, e.g. (3, 4, 1)."""
    if tuple(blender_version) >= PRINCIPLED_V2_VERSION:
        return dict(_PRINCIPLED_SOCKETS_4X)
    return dict(_PRINCIPLED_SOCKETS_3X)


def specular_from_ior_level(specular_ior_level, ior):
    """Blender 4's "Specular IOR Level" (with the IOR) → Blender 3.4's "Specular" (0..1).

    Cycles 4 scales the dielectric F0 from the IOR by 2 · level; Blender 3.4 has F0 = 0.08 ·
    specular. The result is not clamped (see ``clamp_material_fields``).
    """
    ior = max(float(ior), MIN_IOR)
    f0_from_ior = ((ior - 1.0) / (ior + 1.0)) ** 2
    f0 = f0_from_ior * float(specular_ior_level) / NEUTRAL_SPECULAR_IOR_LEVEL
    return f0 / SPECULAR_F0_SCALE


def ior_level_from_specular(specular, ior):
    """Blender 3.4's "Specular" (0..1) → Blender 4's "Specular IOR Level" at this IOR.

    The inverse of ``specular_from_ior_level``: the level whose F0 = ((ior − 1) / (ior + 1))² ·
    2 · level equals 0.08 · specular. An IOR of 1 or less reflects nothing whatever the level,
    so a non-zero specular has no level there (ValueError).
    """
    ior = max(float(ior), MIN_IOR)
    f0_from_ior = ((ior - 1.0) / (ior + 1.0)) ** 2
    f0 = SPECULAR_F0_SCALE * float(specular)
    if f0 == 0.0:
        return 0.0
    if f0_from_ior == 0.0:
        raise ValueError(f"specular {specular} needs an IOR above {MIN_IOR} in Blender 4's "
                         f"Principled BSDF (F0 comes from the IOR); got IOR {ior}")
    return f0 / f0_from_ior * NEUTRAL_SPECULAR_IOR_LEVEL


def rgb(color):
    """The first three components of a colour (Blender colour sockets are RGBA)."""
    return tuple(float(c) for c in tuple(color)[:3])


def material_fields_from_principled(values, blender_version,
                                    distribution=DEFAULT_PRINCIPLED_DISTRIBUTION):
    """shgi.Material fields from a Principled BSDF's input values.

    values: {socket name: default value} for the node's inputs (colours as 3 or 4 floats).
    distribution: the node's ``distribution`` (used from Blender 4.0; ValueError for one SHGI
    does not render). Returns a dict of fields, not yet clamped to SHGI's ranges.
    """
    names = principled_socket_names(blender_version)
    fields = {
        "base_color": rgb(values[names["base_color"]]),
        "metallic": float(values[names["metallic"]]),
        "roughness": float(values[names["roughness"]]),
        "ior": float(values[names["ior"]]),
        "transmission": float(values[names["transmission"]]),
        "emission_color": rgb(values[names["emission_color"]]),
        "emission_strength": float(values[names["emission_strength"]]),
    }
    specular = float(values[names["specular"]])
    if tuple(blender_version) >= PRINCIPLED_V2_VERSION:
        specular = specular_from_ior_level(specular, fields["ior"])
        if distribution not in PRINCIPLED_DISTRIBUTIONS:
            raise ValueError(f"Principled BSDF distribution {distribution!r} is not one of "
                             f"{list(PRINCIPLED_DISTRIBUTIONS)}")
        fields["diffuse_model"] = shgi.DiffuseModel.LAMBERT
        fields["principled_model"] = shgi.PrincipledModel.V2
        fields["distribution"] = PRINCIPLED_DISTRIBUTIONS[distribution]
    fields["specular"] = specular
    return fields


def material_fields_from_emission(color, strength):
    """shgi.Material fields for a plain Emission shader: it emits and reflects nothing."""
    return {"base_color": (0.0, 0.0, 0.0), "specular": 0.0, "metallic": 0.0,
            "emission_color": rgb(color), "emission_strength": float(strength)}


def material_fields_from_diffuse(color):
    """shgi.Material fields for a Diffuse BSDF: Lambert (its Oren–Nayar roughness is ignored)."""
    return {"base_color": rgb(color), "specular": 0.0, "metallic": 0.0, "roughness": 1.0,
            "diffuse_model": shgi.DiffuseModel.LAMBERT}


def fallback_material_fields():
    """The documented fallback for anything the exporter cannot read: grey 0.8, roughness 0.5."""
    return {"base_color": FALLBACK_BASE_COLOR, "roughness": FALLBACK_ROUGHNESS}


_UNIT_RANGE_FIELDS = ("metallic", "roughness", "specular", "transmission")


def clamp_material_fields(fields):
    """(fields clamped to SHGI's ranges, [names of the fields that changed]).

    Blender lets metallic, roughness, specular and transmission leave [0, 1], colours and
    strengths go negative and the IOR drop below 1; SHGI rejects those, so they are clamped.
    """
    clamped, changed = dict(fields), []
    for name in _UNIT_RANGE_FIELDS:
        if name in clamped:
            clamped[name] = min(max(clamped[name], 0.0), 1.0)
    if "ior" in clamped:
        clamped["ior"] = max(clamped["ior"], MIN_IOR)
    for name in ("base_color", "emission_color"):
        if name in clamped:
            clamped[name] = tuple(max(c, 0.0) for c in clamped[name])
    if "emission_strength" in clamped:
        clamped["emission_strength"] = max(clamped["emission_strength"], 0.0)
    for name, value in fields.items():
        if clamped[name] != value:
            changed.append(name)
    return clamped, changed


def texture_needs_srgb_decode(colorspace_name, is_float):
    """True when Image.pixels holds sRGB-encoded values that must be decoded to linear.

    Blender converts float images to scene linear when it loads them; byte images keep their
    encoded values in Image.pixels.
    """
    return (not is_float) and colorspace_name in SRGB_COLORSPACES


def texture_colorspace_is_known(colorspace_name):
    """True for colour spaces the exporter handles exactly (sRGB, linear and data)."""
    return colorspace_name in SRGB_COLORSPACES or colorspace_name in LINEAR_COLORSPACES


def light_fields(light_type, energy, color, matrix_world, *, shadow_soft_size=0.0,
                 spot_size=math.pi / 4, spot_blend=0.15, angle=0.0, shape="SQUARE", size=1.0,
                 size_y=1.0, visible_camera=False, portal=False, name="light",
                 blender_version=NATIVE_LIGHT_UNITS_VERSION, exposure=0.0):
    """shgi.Light fields from a Blender light's properties (Blender's names and units).

    energy: ``Light.energy`` — W for point, spot and area ("Power"), W/m² for the sun
    ("Strength"), in the units of `blender_version` (an area light's power is converted to
    SHGI's, Blender 3.4's, from Blender 4.0 on). exposure: ``Light.exposure`` (Blender 5.0),
    which scales the energy by 2^exposure. shadow_soft_size: the point/spot "Radius" in m.
    spot_size, angle: radians.
    size, size_y: the area light's sides or diameters in m (size_y only for RECTANGLE/ELLIPSE).
    visible_camera: the object's ``visible_camera`` (False for Blender's lights by default).
    portal: Cycles' ``light.cycles.is_portal`` (area lights only; ignored for other types, as
    Blender shows the option only for area lights).
    """
    if light_type not in LIGHT_TYPES:
        raise ValueError(f"light {name!r}: type {light_type!r} is not one of {list(LIGHT_TYPES)}")
    fields = {"name": name, "type": LIGHT_TYPES[light_type], "color": rgb(color),
              "world_from_light": row_major(matrix_world),
              "visible_camera": bool(visible_camera)}
    energy = float(energy) * 2.0 ** float(exposure)
    is_sun = light_type == "SUN"
    exposure_factor = " × 2^Exposure" if exposure else ""
    problem = emission_problem(color, energy,
                               f"{'Strength' if is_sun else 'Power'}{exposure_factor} × Color",
                               IRRADIANCE_UNIT if is_sun else POWER_UNIT)
    if problem is not None:
        raise ValueError(f"{problem}; lower it")
    if light_type == "SUN":
        fields.update(strength=energy, angle=float(angle))
        return fields
    fields["power"] = energy
    if light_type in ("POINT", "SPOT"):
        fields["radius"] = float(shadow_soft_size)
    if light_type == "SPOT":
        fields.update(spot_size=float(spot_size), spot_blend=float(spot_blend),
                      spot_cone_cosine=tuple(blender_version) < SPOT_WITHOUT_CONE_COSINE_VERSION)
    if light_type == "AREA":
        if shape not in AREA_SHAPES:
            raise ValueError(f"light {name!r}: area shape {shape!r} is not one of "
                             f"{list(AREA_SHAPES)}")
        second_side = size_y if shape in AREA_SHAPES_WITH_SIZE_Y else size
        fields.update(shape=AREA_SHAPES[shape], size_x=float(size), size_y=float(second_side),
                      portal=bool(portal))
        if tuple(blender_version) >= AREA_LIGHT_PI_VERSION:
            fields["power"] *= AREA_POWER_TO_NATIVE_FROM_4_0
    return fields


# Light settings of Blender 4.x/5.0 that SHGI does not render, with the value at which they
# change nothing (their defaults).
IGNORED_LIGHT_SETTINGS = {"use_temperature": False, "normalize": True}


def ignored_light_settings(values):
    """Names of the light settings in `values` ({property: value}) that SHGI ignores but that
    are in use."""
    return _in_use(values, IGNORED_LIGHT_SETTINGS)


def render_resolution(resolution_x, resolution_y, resolution_percentage):
    """Blender's rendered size in pixels: size × percentage / 100, rounded down, at least 1."""
    return (max(1, int(resolution_x) * int(resolution_percentage) // 100),
            max(1, int(resolution_y) * int(resolution_percentage) // 100))


def camera_fields(camera_type, matrix_world, *, lens, sensor_width, sensor_height, sensor_fit,
                  ortho_scale, shift_x, shift_y, clip_start, clip_end, resolution_x,
                  resolution_y, resolution_percentage):
    """shgi.Camera fields from Blender's camera data and render size (Blender's names, mm/m).

    camera_type: "PERSP" or "ORTHO" (ValueError otherwise: SHGI has no panoramic camera).
    """
    if camera_type not in CAMERA_TYPES:
        raise ValueError(f"camera type {camera_type!r} is not supported; use one of "
                         f"{list(CAMERA_TYPES)}")
    if sensor_fit not in SENSOR_FITS:
        raise ValueError(f"sensor_fit {sensor_fit!r} is not one of {list(SENSOR_FITS)}")
    width, height = render_resolution(resolution_x, resolution_y, resolution_percentage)
    return {"type": CAMERA_TYPES[camera_type], "lens": float(lens),
            "sensor_width": float(sensor_width), "sensor_height": float(sensor_height),
            "sensor_fit": SENSOR_FITS[sensor_fit], "ortho_scale": float(ortho_scale),
            "shift_x": float(shift_x), "shift_y": float(shift_y),
            "clip_start": float(clip_start), "clip_end": float(clip_end),
            "resolution_x": width, "resolution_y": height,
            "world_from_camera": row_major(matrix_world)}


def world_fields(color, strength):
    """shgi.World fields: the Background's colour and strength (radiance = colour × strength).
    ValueError when their product is not finite or brighter than MAX_EMISSION."""
    problem = emission_problem(color, strength, "Background Color × Strength", RADIANCE_UNIT)
    if problem is not None:
        raise ValueError(f"{problem}; lower it")
    return {"color": tuple(max(c, 0.0) for c in rgb(color)), "strength": max(float(strength), 0.0)}


def equirect_average(pixels):
    """Solid-angle weighted mean RGB of an equirectangular image (H, W, ≥3), row 0 at the bottom.

    Row i spans latitudes around ((i + 0.5) / H − 0.5) · π; its solid angle is ∝ cos(latitude).
    Used as the uniform colour of a textured world.
    """
    pixels = np.asarray(pixels, dtype=np.float64)
    if pixels.ndim != 3 or pixels.shape[2] < 3 or pixels.shape[0] == 0 or pixels.shape[1] == 0:
        raise ValueError(f"pixels: shape {pixels.shape} is not (H, W, 3 or 4)")
    height = pixels.shape[0]
    latitude = ((np.arange(height) + 0.5) / height - 0.5) * math.pi
    weights = np.cos(latitude)
    row_means = pixels[:, :, :3].mean(axis=1)
    return tuple(float(c) for c in (weights[:, None] * row_means).sum(axis=0) / weights.sum())


def row_major(matrix):
    """A 4 × 4 float64 numpy array from a Blender Matrix (its rows) or any nested sequence.

    mathutils.Matrix iterates over rows, so ``np.array(matrix_world)`` is already row-major with
    the translation in the last column, as shgi expects.
    """
    array = np.array([list(row) for row in matrix], dtype=np.float64)
    if array.shape != (4, 4):
        raise ValueError(f"matrix: shape {array.shape} is not (4, 4)")
    return array


# Principled inputs SHGI does not render, with the value at which they have no effect
# (3.x and 4.x names; Blender 4.3 added "Diffuse Roughness", an Oren–Nayar diffuse). A material
# using them gets a warning naming them.
IGNORED_PRINCIPLED_INPUTS = {
    "Subsurface": 0.0, "Subsurface Weight": 0.0, "Sheen": 0.0, "Sheen Weight": 0.0,
    "Clearcoat": 0.0, "Coat Weight": 0.0, "Anisotropic": 0.0, "Alpha": 1.0,
    "Diffuse Roughness": 0.0,
}


def ignored_principled_inputs(values):
    """Names of the Principled inputs in `values` that SHGI ignores but that are in use."""
    return _in_use(values, IGNORED_PRINCIPLED_INPUTS)


def _in_use(values, neutral_values):
    """Names in `neutral_values` ({name: value that changes nothing}) whose value in `values`
    differs from it."""
    return [name for name, neutral in neutral_values.items()
            if name in values and values[name] != neutral]
