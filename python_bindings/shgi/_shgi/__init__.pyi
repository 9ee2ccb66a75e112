"""
SHGI native core: SH maths, scenes on Embree, EXR/PNG I/O, glTF/OBJ loading (see the shgi package).
"""
from __future__ import annotations
import collections.abc
import numpy
import numpy.typing
from shgi import Cancelled
import typing
from . import sh
__all__ = ['AreaShape', 'Camera', 'CameraType', 'Cancelled', 'CausticMode', 'DiffuseModel', 'FaceEstimator', 'GiSolver', 'IndirectField', 'Instance', 'InstantGi', 'InstantGiField', 'InstantGiFilter', 'InstantGiSettings', 'LatticeInterpolation', 'Light', 'LightType', 'LightmapFilterSettings', 'LightmapSettings', 'LightmapTexels', 'LogLevel', 'MAX_COORDINATE', 'MAX_LIGHTMAP_RESOLUTION', 'Material', 'Mesh', 'MicrofacetDistribution', 'NativeMethod', 'NormalMapSpace', 'PathTracer', 'PathTracerSettings', 'PhotonBatch', 'PhotonLattice', 'PhotonLatticeSettings', 'PixelFilter', 'PreviewRenderer', 'PreviewSettings', 'PrincipledModel', 'ProbeField', 'ProbeGrid', 'ProbeGridSettings', 'ProbeLookupSettings', 'ProbeVolume', 'Progress', 'PropagationField', 'PropagationSettings', 'PropagationVolume', 'RadianceField', 'RadianceFieldSettings', 'RouletteSurvival', 'Scene', 'SensorFit', 'TexelMap', 'TexelRasterSettings', 'Texture', 'UnoccludeSettings', 'World', 'WorldSampling', 'bake_lightmap', 'dilate_lightmap', 'filter_lightmap', 'lightmap_read_tiles', 'lightmap_shard_tiles', 'lightmap_tile_count', 'linear_from_srgb', 'load_gltf', 'load_obj', 'log_level', 'make_native_solver', 'max_threads', 'memory_limits', 'merge_lightmap', 'native_methods', 'propagation_steps', 'rasterize_texels', 'read_exr', 'read_exr_info', 'render_path_traced', 'render_preview', 'reserved_method_numbers', 'set_log_level', 'set_log_sink', 'set_max_threads', 'sh', 'srgb_from_linear', 'trace_photon_batch', 'unocclude', 'version', 'write_exr', 'write_png']
class AreaShape:
    """
    Blender's area light shapes.
    
    Members:
    
      SQUARE
    
      RECTANGLE
    
      DISK
    
      ELLIPSE
    """
    DISK: typing.ClassVar[AreaShape]  # value = <AreaShape.DISK: 2>
    ELLIPSE: typing.ClassVar[AreaShape]  # value = <AreaShape.ELLIPSE: 3>
    RECTANGLE: typing.ClassVar[AreaShape]  # value = <AreaShape.RECTANGLE: 1>
    SQUARE: typing.ClassVar[AreaShape]  # value = <AreaShape.SQUARE: 0>
    __members__: typing.ClassVar[dict[str, AreaShape]]  # value = {'SQUARE': <AreaShape.SQUARE: 0>, 'RECTANGLE': <AreaShape.RECTANGLE: 1>, 'DISK': <AreaShape.DISK: 2>, 'ELLIPSE': <AreaShape.ELLIPSE: 3>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: AreaShape) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: AreaShape) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class Camera:
    """
    A Blender camera (see scene/camera.h).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        Camera(**fields): Blender's default camera data.
        """
    def generate_ray(self, x: typing.SupportsFloat | typing.SupportsIndex, y: typing.SupportsFloat | typing.SupportsIndex) -> tuple[tuple, tuple, float, float]:
        """
        (origin, direction, tmin, tmax) of the ray through film point (x, y) in pixels from the top-left corner; direction is unit length, tmin/tmax the clip distances.
        """
    def generate_rays(self, film: typing.Any) -> tuple[numpy.typing.NDArray[numpy.float32], numpy.typing.NDArray[numpy.float32]]:
        """
        (origins (N, 3), directions (N, 3)) of the rays through film points (N, 2) in pixels from the top-left corner (pixel centres at +0.5); directions are unit length.
        """
    def project(self, point: typing.Any) -> typing.Any:
        """
        Film position (x, y) in pixels of a world point, or None when it is behind.
        """
    @property
    def clip_end(self) -> float:
        """
        m.
        """
    @clip_end.setter
    def clip_end(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def clip_start(self) -> float:
        """
        m.
        """
    @clip_start.setter
    def clip_start(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def lens(self) -> float:
        """
        Focal length in mm (perspective).
        """
    @lens.setter
    def lens(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ortho_scale(self) -> float:
        """
        m across the fitted axis.
        """
    @ortho_scale.setter
    def ortho_scale(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def resolution_x(self) -> int:
        """
        Render width in pixels.
        """
    @resolution_x.setter
    def resolution_x(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def resolution_y(self) -> int:
        """
        Render height in pixels.
        """
    @resolution_y.setter
    def resolution_y(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def sensor_fit(self) -> SensorFit:
        """
        SensorFit.
        """
    @sensor_fit.setter
    def sensor_fit(self, arg0: SensorFit) -> None:
        ...
    @property
    def sensor_height(self) -> float:
        """
        mm.
        """
    @sensor_height.setter
    def sensor_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def sensor_width(self) -> float:
        """
        mm.
        """
    @sensor_width.setter
    def sensor_width(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def shift_x(self) -> float:
        """
        In units of the fitted dimension.
        """
    @shift_x.setter
    def shift_x(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def shift_y(self) -> float:
        """
        In units of the fitted dimension.
        """
    @shift_y.setter
    def shift_y(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def type(self) -> CameraType:
        """
        CameraType.
        """
    @type.setter
    def type(self, arg0: CameraType) -> None:
        ...
    @property
    def world_from_camera(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (4, 4) row-major matrix_world; the camera looks down its local -Z, +Y up.
        """
    @world_from_camera.setter
    def world_from_camera(self, arg1: typing.Any) -> None:
        ...
class CameraType:
    """
    Perspective or orthographic.
    
    Members:
    
      PERSPECTIVE
    
      ORTHOGRAPHIC
    """
    ORTHOGRAPHIC: typing.ClassVar[CameraType]  # value = <CameraType.ORTHOGRAPHIC: 1>
    PERSPECTIVE: typing.ClassVar[CameraType]  # value = <CameraType.PERSPECTIVE: 0>
    __members__: typing.ClassVar[dict[str, CameraType]]  # value = {'PERSPECTIVE': <CameraType.PERSPECTIVE: 0>, 'ORTHOGRAPHIC': <CameraType.ORTHOGRAPHIC: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: CameraType) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: CameraType) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class CausticMode:
    """
    Where caustic photons (light → specular+ → diffuse) go.
    
    Members:
    
      OFF
    
      LATTICE
    
      PHOTON_MAP
    """
    LATTICE: typing.ClassVar[CausticMode]  # value = <CausticMode.LATTICE: 1>
    OFF: typing.ClassVar[CausticMode]  # value = <CausticMode.OFF: 0>
    PHOTON_MAP: typing.ClassVar[CausticMode]  # value = <CausticMode.PHOTON_MAP: 2>
    __members__: typing.ClassVar[dict[str, CausticMode]]  # value = {'OFF': <CausticMode.OFF: 0>, 'LATTICE': <CausticMode.LATTICE: 1>, 'PHOTON_MAP': <CausticMode.PHOTON_MAP: 2>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: CausticMode) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: CausticMode) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class DiffuseModel:
    """
    The diffuse lobe of a Material.
    
    Members:
    
      PRINCIPLED : Principled BSDF's diffuse (Burley, with retro-reflection at high roughness)
    
      LAMBERT : Lambert, as Blender's Diffuse BSDF
    """
    LAMBERT: typing.ClassVar[DiffuseModel]  # value = <DiffuseModel.LAMBERT: 1>
    PRINCIPLED: typing.ClassVar[DiffuseModel]  # value = <DiffuseModel.PRINCIPLED: 0>
    __members__: typing.ClassVar[dict[str, DiffuseModel]]  # value = {'PRINCIPLED': <DiffuseModel.PRINCIPLED: 0>, 'LAMBERT': <DiffuseModel.LAMBERT: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: DiffuseModel) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: DiffuseModel) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class FaceEstimator:
    """
    How photon flux becomes radiance on the radiance grid's cell faces.
    
    Members:
    
      PROJECTED_AREA
    
      PAPER
    """
    PAPER: typing.ClassVar[FaceEstimator]  # value = <FaceEstimator.PAPER: 1>
    PROJECTED_AREA: typing.ClassVar[FaceEstimator]  # value = <FaceEstimator.PROJECTED_AREA: 0>
    __members__: typing.ClassVar[dict[str, FaceEstimator]]  # value = {'PROJECTED_AREA': <FaceEstimator.PROJECTED_AREA: 0>, 'PAPER': <FaceEstimator.PAPER: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: FaceEstimator) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: FaceEstimator) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class GiSolver:
    """
    
    The interface every GI method implements (PhotonLattice, ProbeGrid, ...): refine(progress) runs
    one refinement pass, reset(progress) forgets every pass, current_field() is the IndirectField to
    render (unchanged until the next refine or reset), passes counts the passes, stage_seconds the
    wall time of the last pass's stages, memory_bytes what the solution holds. Subclass it in
    Python to prototype a method (register it with shgi.register_method).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self) -> None:
        """
        For Python subclasses.
        """
class IndirectField:
    """
    
    Indirect incident light solved by a solver (PhotonLattice, ...), read by the renderers.
    
    Units: radiance W m^-2 sr^-1, irradiance W m^-2; only indirect light (direct light is computed
    exactly by the consumer). Queries take arrays of points and unit normals.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def irradiance(self, points: typing.Any, normals: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, 3) irradiance in W/m^2 at points (N, 3) on surfaces with normals (N, 3).
        """
    def radiance_sh(self, point: typing.Any, normal: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
        """
        Incident radiance SH at a point for a surface with that normal: float32 (coefficients, 3), index l(l+1)+m, coefficient-major RGB.
        """
class Instance:
    """
    A placement of a mesh in the world.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @property
    def mesh_id(self) -> int:
        """
        Index of the instanced mesh.
        """
    @property
    def name(self) -> str:
        """
        The object's name.
        """
    @property
    def world_from_object(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (4, 4) row-major matrix_world.
        """
class InstantGi(GiSolver):
    """
    
    Instant GI with a discontinuity-aware screen-space SH filter (seed 004): VPLs from traced light
    paths, dealt into sets_x x sets_y interleaved sets; each pixel gathers its set's VPLs as L2 SH of
    the incident radiance with exact shadow rays, the SH is blended over an interleave-wide window
    that stops at depth, geometric-normal and object edges, and each pixel is shaded with its own
    shading normal (normal-map detail kept).
    
    Each refine() adds a pass of new VPLs to every set. current_field() is an immutable snapshot.
    After editing and re-committing the scene, call reset().
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, scene: Scene, settings: InstantGiSettings = ..., progress: Progress = None) -> None:
        """
        A solver with no VPLs yet (the scene must be committed).
        """
    def current_field(self) -> InstantGiField:
        """
        The InstantGiField of the last pass (safe to render while refine() runs).
        """
    def refine(self, progress: Progress = None) -> None:
        """
        One pass: traces light paths and adds their VPLs to the sets (GIL released). Raises shgi.Cancelled on cancel, keeping the previous sets.
        """
    def reset(self, progress: Progress = None) -> None:
        """
        Forgets every pass (re-reads the scene).
        """
    @property
    def memory_bytes(self) -> int:
        """
        Bytes held by the VPL sets.
        """
    @property
    def passes(self) -> int:
        """
        Passes so far.
        """
    @property
    def settings(self) -> InstantGiSettings:
        """
        A copy of the settings.
        """
    @property
    def stage_seconds(self) -> list:
        """
        [(stage, seconds)] of the last pass: vpl_trace, vpl_sets (reflection of later hits and dealing into sets).
        """
class InstantGiField(IndirectField):
    """
    Immutable VPL sets as an IndirectField: the preview renderer's first surfaces are lit by the interleaved sets and the screen-space filter; lookups elsewhere gather every VPL.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def sample_passes(self, sample: typing.SupportsIndex) -> list[int]:
        """
        The passes preview sample `sample` gathers (passes_per_sample), in order.
        """
    @property
    def frame_timings(self) -> dict:
        """
        {gather, filter, shade}: seconds of the latest frame this field lit.
        """
    @property
    def lookup_counts(self) -> dict:
        """
        {lookups, vpls}: the field's lookups beyond the first surfaces (through glass and mirrors; bakes' too) and the VPLs, sky directions and lamp samples they read (a shadow ray each at most), since the preview renderer's latest frame with it began (or since the field was made).
        """
    @property
    def passes(self) -> int:
        """
        Passes of VPLs it holds.
        """
    @property
    def set_sizes(self) -> list[int]:
        """
        VPLs per set, set (i, j) at index j * sets_x + i.
        """
    @property
    def vpl_count(self) -> int:
        """
        VPLs in all sets.
        """
class InstantGiFilter:
    """
    What the Instant GI's screen-space filter blends between pixels.
    
    Members:
    
      SH
    
      IRRADIANCE
    
      STRICT
    
      NONE
    """
    IRRADIANCE: typing.ClassVar[InstantGiFilter]  # value = <InstantGiFilter.IRRADIANCE: 1>
    NONE: typing.ClassVar[InstantGiFilter]  # value = <InstantGiFilter.NONE: 3>
    SH: typing.ClassVar[InstantGiFilter]  # value = <InstantGiFilter.SH: 0>
    STRICT: typing.ClassVar[InstantGiFilter]  # value = <InstantGiFilter.STRICT: 2>
    __members__: typing.ClassVar[dict[str, InstantGiFilter]]  # value = {'SH': <InstantGiFilter.SH: 0>, 'IRRADIANCE': <InstantGiFilter.IRRADIANCE: 1>, 'STRICT': <InstantGiFilter.STRICT: 2>, 'NONE': <InstantGiFilter.NONE: 3>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: InstantGiFilter) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: InstantGiFilter) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class InstantGiSettings:
    """
    Settings of the InstantGi solver (seed 004); every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        InstantGiSettings(**fields), e.g. InstantGiSettings(sets_x=3, sets_y=3).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def clamp_distance(self) -> float:
        """
        m: a VPL closer than this counts as this far (the 1/d^2 spike's clamp; 0 = off) (0.05).
        """
    @clamp_distance.setter
    def clamp_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def depth_threshold(self) -> float:
        """
        Neighbours whose depth differs by more than this fraction are not blended (0.1).
        """
    @depth_threshold.setter
    def depth_threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def filter_direct(self) -> bool:
        """
        Direct light through the SH filter, as the paper filters it: the world's as directional VPLs (photons_per_set per set and pass), the point, spot, area and sun lights' as samples per set (one for a delta light, photons_per_set per pass for one with extent) and the emissive triangles' as photons_per_set samples per set and pass (each triangle by its power), each with its exact shadow ray; next-event estimation then leaves them out (False).
        """
    @filter_direct.setter
    def filter_direct(self, arg0: bool) -> None:
        ...
    @property
    def filter_mode(self) -> InstantGiFilter:
        """
        InstantGiFilter: SH (the paper's), IRRADIANCE (each pixel's irradiance, same edges), STRICT (irradiance, also stopping at shading-normal changes), NONE (each pixel its own set).
        """
    @filter_mode.setter
    def filter_mode(self, arg0: InstantGiFilter) -> None:
        ...
    @property
    def gather_cut_windows(self) -> bool:
        """
        Pixels whose filter window an edge cuts gather every set themselves and skip the filter: no blur of light across the edge's side, at sets_x x sets_y times those pixels' shadow rays (False).
        """
    @gather_cut_windows.setter
    def gather_cut_windows(self, arg0: bool) -> None:
        ...
    @property
    def gather_near_radius(self) -> float:
        """
        Final gather: where a gather ray lands, VPLs nearer than this (m) are read from every set, the farther ones from the ray's one set: less noise at the same mean; 0 = off (0.25).
        """
    @gather_near_radius.setter
    def gather_near_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_bounces(self) -> int:
        """
        Glossy scatterings of a light path, a budget of their own beside vpl_bounces, 0..64; 4 matches Cycles' default glossy bounces.
        """
    @glossy_bounces.setter
    def glossy_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_from_vpls(self) -> bool:
        """
        Glossy lobes of roughness 0.3 and above weigh each VPL by the lobe itself instead of reading the L2 SH: sharper glossy light, the same mean (False).
        """
    @glossy_from_vpls.setter
    def glossy_from_vpls(self, arg0: bool) -> None:
        ...
    @property
    def glossy_vpls(self) -> bool:
        """
        A VPL's surface scatters with its rough glossy lobes too, as if diffuse; False: its diffuse lobe only (True).
        """
    @glossy_vpls.setter
    def glossy_vpls(self, arg0: bool) -> None:
        ...
    @property
    def near_field_reach(self) -> float:
        """
        VPLs nearer to a pixel than this many times its filter window's reach (the farthest neighbour it blends) are gathered from every set and kept out of the filter, whose blur they would bias; 0..64, 0 = off (4).
        """
    @near_field_reach.setter
    def near_field_reach(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_threshold(self) -> float:
        """
        Neighbours whose geometric normals' cosine is below this are not blended (0.9).
        """
    @normal_threshold.setter
    def normal_threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def passes_per_sample(self) -> int:
        """
        Passes of VPLs a preview sample gathers, 1..65536: sample i gathers the k passes after sample i - 1's (around the solve's passes), so a frame's samples average more passes than one gathers; with no more passes than this, every sample gathers them all (4).
        """
    @passes_per_sample.setter
    def passes_per_sample(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def photons_per_set(self) -> int:
        """
        Light paths traced per set and pass; each leaves a VPL at its first vpl_bounces hits (16).
        """
    @photons_per_set.setter
    def photons_per_set(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def sets_x(self) -> int:
        """
        n: VPL sets across; pixel (x, y) uses set (x mod n, y mod m), 1..16 (4).
        """
    @sets_x.setter
    def sets_x(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def sets_y(self) -> int:
        """
        m: VPL sets down, 1..16 (4).
        """
    @sets_y.setter
    def sets_y(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def vpl_bounces(self) -> int:
        """
        Hits of a light path that leave a VPL: 1 is one bounce of indirect light (4).
        """
    @vpl_bounces.setter
    def vpl_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
class LatticeInterpolation:
    """
    How lattices are sampled.
    
    Members:
    
      TRILINEAR
    
      CUBIC
    """
    CUBIC: typing.ClassVar[LatticeInterpolation]  # value = <LatticeInterpolation.CUBIC: 1>
    TRILINEAR: typing.ClassVar[LatticeInterpolation]  # value = <LatticeInterpolation.TRILINEAR: 0>
    __members__: typing.ClassVar[dict[str, LatticeInterpolation]]  # value = {'TRILINEAR': <LatticeInterpolation.TRILINEAR: 0>, 'CUBIC': <LatticeInterpolation.CUBIC: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: LatticeInterpolation) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: LatticeInterpolation) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class Light:
    """
    A Blender light with Cycles' units (see scene/light.h).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        Light(**fields): a default point light with the given fields set.
        """
    @property
    def angle(self) -> float:
        """
        rad: sun's angular diameter, [0, pi).
        """
    @angle.setter
    def angle(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def color(self) -> tuple:
        """
        Linear RGB, each >= 0.
        """
    @color.setter
    def color(self, arg1: typing.Any) -> None:
        ...
    @property
    def name(self) -> str:
        """
        Blender's light object name.
        """
    @name.setter
    def name(self, arg0: str) -> None:
        ...
    @property
    def portal(self) -> bool:
        """
        Cycles' area light Portal: emits nothing, aims world light through an opening (area lights only).
        """
    @portal.setter
    def portal(self, arg0: bool) -> None:
        ...
    @property
    def power(self) -> float:
        """
        W (point, spot, area).
        """
    @power.setter
    def power(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def radius(self) -> float:
        """
        m: point/spot radius (0 = a true point).
        """
    @radius.setter
    def radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def shape(self) -> AreaShape:
        """
        AreaShape.
        """
    @shape.setter
    def shape(self, arg0: AreaShape) -> None:
        ...
    @property
    def size_x(self) -> float:
        """
        m: area light size along local X.
        """
    @size_x.setter
    def size_x(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def size_y(self) -> float:
        """
        m: area light size along local Y.
        """
    @size_y.setter
    def size_y(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def spot_blend(self) -> float:
        """
        [0, 1].
        """
    @spot_blend.setter
    def spot_blend(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def spot_cone_cosine(self) -> bool:
        """
        True (Blender 3.x): the spot's falloff includes cos(angle to its axis); the exporter sets False from Blender 4.0, whose Cycles drops it.
        """
    @spot_cone_cosine.setter
    def spot_cone_cosine(self, arg0: bool) -> None:
        ...
    @property
    def spot_size(self) -> float:
        """
        rad: full cone angle, (0, pi].
        """
    @spot_size.setter
    def spot_size(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def strength(self) -> float:
        """
        W/m^2 (sun).
        """
    @strength.setter
    def strength(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def type(self) -> LightType:
        """
        LightType.
        """
    @type.setter
    def type(self, arg0: LightType) -> None:
        ...
    @property
    def visible_camera(self) -> bool:
        """
        Blender's Object.visible_camera: camera rays see the light (False, as Blender's lights).
        """
    @visible_camera.setter
    def visible_camera(self, arg0: bool) -> None:
        ...
    @property
    def world_from_light(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (4, 4) row-major matrix_world; the light emits along its local -Z.
        """
    @world_from_light.setter
    def world_from_light(self, arg1: typing.Any) -> None:
        ...
class LightType:
    """
    Blender's light types.
    
    Members:
    
      POINT
    
      SPOT
    
      SUN
    
      AREA
    """
    AREA: typing.ClassVar[LightType]  # value = <LightType.AREA: 3>
    POINT: typing.ClassVar[LightType]  # value = <LightType.POINT: 0>
    SPOT: typing.ClassVar[LightType]  # value = <LightType.SPOT: 1>
    SUN: typing.ClassVar[LightType]  # value = <LightType.SUN: 2>
    __members__: typing.ClassVar[dict[str, LightType]]  # value = {'POINT': <LightType.POINT: 0>, 'SPOT': <LightType.SPOT: 1>, 'SUN': <LightType.SUN: 2>, 'AREA': <LightType.AREA: 3>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: LightType) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: LightType) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class LightmapFilterSettings:
    """
    Edge-aware a-trous filter that never crosses UV charts.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        LightmapFilterSettings(**fields)
        """
    @property
    def iterations(self) -> int:
        """
        A-trous passes, 0 = off (2).
        """
    @iterations.setter
    def iterations(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def luminance_sigma(self) -> float:
        """
        Standard deviations of luminance before weight 1/e (4).
        """
    @luminance_sigma.setter
    def luminance_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_power(self) -> float:
        """
        Normal weight sharpness (64).
        """
    @normal_power.setter
    def normal_power(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def position_sigma(self) -> float:
        """
        Texels off the texel's plane before weight 1/e (1).
        """
    @position_sigma.setter
    def position_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class LightmapSettings:
    """
    
    What and how a lightmap is baked; every field has a default. Content (Cycles' DIFFUSE bake):
    'DIRECT_INDIRECT' (pass_filter {DIRECT, INDIRECT}), 'DIRECT', 'INDIRECT', or 'FULL' (also COLOR).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        LightmapSettings(**fields)
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def clamp_indirect(self) -> float:
        """
        Light Paths > Clamp Indirect as Cycles': an indirect contribution whose components average more than this is scaled down to it; 0 = off (0).
        """
    @clamp_indirect.setter
    def clamp_indirect(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def content(self) -> str:
        """
        'DIRECT_INDIRECT' (default), 'DIRECT', 'INDIRECT' or 'FULL'.
        """
    @content.setter
    def content(self, arg1: str) -> None:
        ...
    @property
    def diffuse_bounces(self) -> int:
        """
        Cycles' Diffuse bounces (4).
        """
    @diffuse_bounces.setter
    def diffuse_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def directional(self) -> bool:
        """
        Also bake the SH of the incident radiance, of order sh_order (False).
        """
    @directional.setter
    def directional(self, arg0: bool) -> None:
        ...
    @property
    def filter_glossy(self) -> float:
        """
        Light Paths > Filter Glossy as Cycles': after a bounce whose BSDF pdf was below this value, glossy and glass lobes widen to GGX alpha sqrt(1 - pdf / value) / 2, against the caustic fireflies of mirrors seen through diffuse bounces; 0 = off (0).
        """
    @filter_glossy.setter
    def filter_glossy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def final_gather(self) -> bool:
        """
        With a field: each sample traces one ray that reads the field where it lands, with direct light there, instead of reading it at the texel: the field's blocks and leaks are one bounce further away (False).
        """
    @final_gather.setter
    def final_gather(self, arg0: bool) -> None:
        ...
    @property
    def glossy_bounces(self) -> int:
        """
        Cycles' Glossy bounces (4).
        """
    @glossy_bounces.setter
    def glossy_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def light_splits(self) -> int:
        """
        Most emitters one next-event estimate samples, as PathTracerSettings.light_splits (4).
        """
    @light_splits.setter
    def light_splits(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def max_bounces(self) -> int:
        """
        Cycles' Total bounces (12).
        """
    @max_bounces.setter
    def max_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def samples(self) -> int:
        """
        Samples per texel (256).
        """
    @samples.setter
    def samples(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def sh_order(self) -> int:
        """
        SH order of the directional data: 1 (L1, 4 coefficients per channel) or 2 (L2, 9) (1).
        """
    @sh_order.setter
    def sh_order(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def tile_size(self) -> int:
        """
        Texels per tile side: the unit of work and of shards (16).
        """
    @tile_size.setter
    def tile_size(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def transmission_bounces(self) -> int:
        """
        Cycles' Transmission bounces (12).
        """
    @transmission_bounces.setter
    def transmission_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
class LightmapTexels:
    """
    
    A baked lightmap: arrays (height, width, ...) with row 0 at v = 0 (Blender's Image.pixels order).
    LightmapTexels(color, variance, baked, sh=None) rebuilds one from its arrays (a shard file); sh
    (height, width, 4, 3) is L1, (height, width, 9, 3) L2.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, color: numpy.ndarray, variance: numpy.ndarray, baked: numpy.ndarray, sh: typing.Any = None) -> None:
        ...
    @property
    def baked(self) -> numpy.typing.NDArray[numpy.bool]:
        """
        (H, W) bool: texels this bake computed.
        """
    @property
    def color(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (H, W, 3) float32 light per texel (units: LightmapSettings.content).
        """
    @property
    def directional(self) -> bool:
        ...
    @property
    def height(self) -> int:
        ...
    @property
    def sh(self) -> typing.Any:
        """
        (H, W, 4, 3) float32 L1 SH of incident radiance (index l(l+1)+m) — (H, W, 9, 3) at L2 — or None.
        """
    @property
    def sh_order(self) -> typing.Any:
        """
        SH order of the directional data (1: L1, 2: L2), or None without it.
        """
    @property
    def variance(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (H, W) float32 variance of each texel's luminance (confidence).
        """
    @property
    def width(self) -> int:
        ...
class LogLevel:
    """
    Severity of a log message.
    
    Members:
    
      DEBUG
    
      INFO
    
      WARNING
    
      ERROR
    """
    DEBUG: typing.ClassVar[LogLevel]  # value = <LogLevel.DEBUG: 0>
    ERROR: typing.ClassVar[LogLevel]  # value = <LogLevel.ERROR: 3>
    INFO: typing.ClassVar[LogLevel]  # value = <LogLevel.INFO: 1>
    WARNING: typing.ClassVar[LogLevel]  # value = <LogLevel.WARNING: 2>
    __members__: typing.ClassVar[dict[str, LogLevel]]  # value = {'DEBUG': <LogLevel.DEBUG: 0>, 'INFO': <LogLevel.INFO: 1>, 'WARNING': <LogLevel.WARNING: 2>, 'ERROR': <LogLevel.ERROR: 3>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: LogLevel) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: LogLevel) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class Material:
    """
    Principled BSDF subset (Blender 3.4 semantics, or 4.x's with principled_model V2), linear Rec.709.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        Material(**fields): a default material with the given fields set, e.g. Material(name='Red', base_color=(0.8, 0.1, 0.1), roughness=0.3).
        """
    def is_emissive(self) -> bool:
        """
        True if the material emits light.
        """
    @property
    def base_color(self) -> tuple:
        """
        Linear RGB albedo.
        """
    @base_color.setter
    def base_color(self, arg1: typing.Any) -> None:
        ...
    @property
    def base_color_texture(self) -> int:
        """
        Index into the scene's textures, or -1 for none.
        """
    @base_color_texture.setter
    def base_color_texture(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def base_color_uv_set(self) -> str:
        """
        UV map used by the texture ('' = the first).
        """
    @base_color_uv_set.setter
    def base_color_uv_set(self, arg0: str) -> None:
        ...
    @property
    def bump_distance(self) -> float:
        """
        Bump Distance in scene units, -1000..1000 (negative: Invert).
        """
    @bump_distance.setter
    def bump_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def bump_strength(self) -> float:
        """
        Bump Strength, 0..1 (0: the unbumped normal).
        """
    @bump_strength.setter
    def bump_strength(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def bump_texture(self) -> int:
        """
        Bump node's Height: index into the scene's textures (its luminance is the height), or -1 for none.
        """
    @bump_texture.setter
    def bump_texture(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def bump_uv_set(self) -> str:
        """
        UV map used by the bump map ('' = the first).
        """
    @bump_uv_set.setter
    def bump_uv_set(self, arg0: str) -> None:
        ...
    @property
    def diffuse_model(self) -> DiffuseModel:
        """
        DiffuseModel (PRINCIPLED; the exporter sets LAMBERT for a Diffuse BSDF).
        """
    @diffuse_model.setter
    def diffuse_model(self, arg0: DiffuseModel) -> None:
        ...
    @property
    def distribution(self) -> MicrofacetDistribution:
        """
        MicrofacetDistribution (GGX; Blender 4's default is MULTISCATTER_GGX).
        """
    @distribution.setter
    def distribution(self, arg0: MicrofacetDistribution) -> None:
        ...
    @property
    def emission_color(self) -> tuple:
        """
        Linear RGB; emitted radiance = emission_color * emission_strength (W m^-2 sr^-1).
        """
    @emission_color.setter
    def emission_color(self, arg1: typing.Any) -> None:
        ...
    @property
    def emission_strength(self) -> float:
        """
        >= 0.
        """
    @emission_strength.setter
    def emission_strength(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ior(self) -> float:
        """
        Index of refraction, >= 1.
        """
    @ior.setter
    def ior(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def metallic(self) -> float:
        """
        0..1.
        """
    @metallic.setter
    def metallic(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def name(self) -> str:
        """
        Blender's material name.
        """
    @name.setter
    def name(self, arg0: str) -> None:
        ...
    @property
    def normal_space(self) -> NormalMapSpace:
        """
        NormalMapSpace of the normal map (TANGENT).
        """
    @normal_space.setter
    def normal_space(self, arg0: NormalMapSpace) -> None:
        ...
    @property
    def normal_strength(self) -> float:
        """
        Normal Map Strength, 0..100 (0: the interpolated normal, 1: the map's).
        """
    @normal_strength.setter
    def normal_strength(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_texture(self) -> int:
        """
        Normal map: index into the scene's textures (non-colour data), or -1 for none.
        """
    @normal_texture.setter
    def normal_texture(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def normal_uv_set(self) -> str:
        """
        UV map used by the normal map ('' = the first).
        """
    @normal_uv_set.setter
    def normal_uv_set(self, arg0: str) -> None:
        ...
    @property
    def principled_model(self) -> PrincipledModel:
        """
        PrincipledModel (V1; the exporter sets V2 from Blender 4.0).
        """
    @principled_model.setter
    def principled_model(self, arg0: PrincipledModel) -> None:
        ...
    @property
    def roughness(self) -> float:
        """
        0..1 (GGX alpha = roughness^2).
        """
    @roughness.setter
    def roughness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def specular(self) -> float:
        """
        0..1 (F0 = 0.08 * specular).
        """
    @specular.setter
    def specular(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def transmission(self) -> float:
        """
        0..1.
        """
    @transmission.setter
    def transmission(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class Mesh:
    """
    A triangle mesh in object space (see scene/mesh.h).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, positions: typing.Any, triangles: typing.Any, normals: typing.Any = None, uvs: typing.Any = None, material_indices: typing.Any = None, name: str = '', tangents: typing.Any = None) -> None:
        """
        Builds a mesh from numpy arrays. positions: (N, 3) float, object space (m); triangles: (T, 3) int vertex indices, counter-clockwise = front; normals: (N, 3) float or None; uvs: (N, 2) float (UV map 'UVMap'), a dict {name: (N, 2)} or None; material_indices: (T,) int or None (all 0); tangents: (N, 4) float (object-space MikkTSpace tangent of the normal map's UV map, then the bitangent sign +-1) or None; NaN or zero tangents are dropped with a warning (no normal map there).
        """
    def __repr__(self) -> str:
        """
        Name and sizes.
        """
    @property
    def material_indices(self) -> numpy.typing.NDArray[numpy.uint32]:
        """
        (T,) uint32 material index per triangle, or empty (all use material 0).
        """
    @material_indices.setter
    def material_indices(self, arg1: typing.Any) -> None:
        ...
    @property
    def name(self) -> str:
        """
        The mesh's name (Blender's mesh data name).
        """
    @name.setter
    def name(self, arg0: str) -> None:
        ...
    @property
    def normals(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, 3) float32 vertex normals, or (0, 3) when the mesh has none.
        """
    @normals.setter
    def normals(self, arg1: typing.Any) -> None:
        ...
    @property
    def positions(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, 3) float32 vertex positions, object space (m).
        """
    @positions.setter
    def positions(self, arg1: typing.Any) -> None:
        ...
    @property
    def tangents(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, 4) float32 vertex tangents (xyz object space, w bitangent sign), or (0, 4).
        """
    @tangents.setter
    def tangents(self, arg1: typing.Any) -> None:
        ...
    @property
    def triangles(self) -> numpy.typing.NDArray[numpy.uint32]:
        """
        (T, 3) uint32 vertex indices per triangle.
        """
    @triangles.setter
    def triangles(self, arg1: typing.Any) -> None:
        ...
    @property
    def uv_sets(self) -> dict:
        """
        Dict {uv map name: (N, 2) float32}, in order (the first is used for textures).
        """
    @uv_sets.setter
    def uv_sets(self, arg1: typing.Any) -> None:
        ...
class MicrofacetDistribution:
    """
    The microfacet distribution of a Material's specular.
    
    Members:
    
      GGX : GGX, single scattering
    
      MULTISCATTER_GGX : Cycles 4's energy-preserving GGX (with principled_model V2)
    """
    GGX: typing.ClassVar[MicrofacetDistribution]  # value = <MicrofacetDistribution.GGX: 0>
    MULTISCATTER_GGX: typing.ClassVar[MicrofacetDistribution]  # value = <MicrofacetDistribution.MULTISCATTER_GGX: 1>
    __members__: typing.ClassVar[dict[str, MicrofacetDistribution]]  # value = {'GGX': <MicrofacetDistribution.GGX: 0>, 'MULTISCATTER_GGX': <MicrofacetDistribution.MULTISCATTER_GGX: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: MicrofacetDistribution) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: MicrofacetDistribution) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class NativeMethod:
    """
    A row of the native method registry (see shgi.methods()).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @property
    def aliases(self) -> list[str]:
        """
        Older names still accepted.
        """
    @property
    def description(self) -> str:
        ...
    @property
    def final_passes(self) -> int:
        """
        Refinement passes of a final solve (F12, bake, CLI).
        """
    @property
    def identifier(self) -> str:
        ...
    @property
    def label(self) -> str:
        ...
    @property
    def number(self) -> int:
        """
        The enum value .blend files store.
        """
    @property
    def settings_type(self) -> str:
        """
        Name of the settings class in shgi.
        """
    @property
    def solves_field(self) -> bool:
        """
        False for the path tracer, which solves nothing.
        """
class NormalMapSpace:
    """
    The space of a Material's normal map texels.
    
    Members:
    
      TANGENT : along the mesh's tangents (Mesh.tangents; glTF's normalTexture)
    
      OBJECT : object space
    
      WORLD : world space
    
      BLENDER_OBJECT : Blender's object space (Y and Z negated)
    
      BLENDER_WORLD : Blender's world space (Y and Z negated)
    """
    BLENDER_OBJECT: typing.ClassVar[NormalMapSpace]  # value = <NormalMapSpace.BLENDER_OBJECT: 3>
    BLENDER_WORLD: typing.ClassVar[NormalMapSpace]  # value = <NormalMapSpace.BLENDER_WORLD: 4>
    OBJECT: typing.ClassVar[NormalMapSpace]  # value = <NormalMapSpace.OBJECT: 1>
    TANGENT: typing.ClassVar[NormalMapSpace]  # value = <NormalMapSpace.TANGENT: 0>
    WORLD: typing.ClassVar[NormalMapSpace]  # value = <NormalMapSpace.WORLD: 2>
    __members__: typing.ClassVar[dict[str, NormalMapSpace]]  # value = {'TANGENT': <NormalMapSpace.TANGENT: 0>, 'OBJECT': <NormalMapSpace.OBJECT: 1>, 'WORLD': <NormalMapSpace.WORLD: 2>, 'BLENDER_OBJECT': <NormalMapSpace.BLENDER_OBJECT: 3>, 'BLENDER_WORLD': <NormalMapSpace.BLENDER_WORLD: 4>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: NormalMapSpace) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: NormalMapSpace) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class PathTracer:
    """
    
    Progressive reference path tracer over a committed Scene with a camera.
    
    render(samples) adds samples to the film; passes() returns every pass so far. The result
    depends only on the seed and the total sample count, not on threads or how the samples
    were split between render() calls.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, scene: Scene, settings: PathTracerSettings = ...) -> None:
        """
        Checks the settings (ValueError) and prepares light sampling.
        """
    def passes(self, names: typing.Any = None) -> dict:
        """
        {pass name: float32 array (H, W, C)}: Combined (RGBA), DiffDir, ..., Normal (XYZ), Depth (1 channel), Denoising Albedo, Denoising Normal (the denoiser's guides, through specular surfaces as Cycles'), with Cycles' meaning; names, e.g. ['Combined'], converts only those (a viewport needs Combined alone).
        """
    def render(self, samples: typing.Any = None, progress: Progress = None) -> None:
        """
        Adds `samples` samples per pixel (default settings.samples) with the GIL released. Raises shgi.Cancelled when progress.cancel() is called; the film is then unchanged.
        """
    @property
    def samples_done(self) -> int:
        """
        Samples per pixel accumulated so far.
        """
class PathTracerSettings:
    """
    Settings of the reference path tracer; every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        PathTracerSettings(**fields), e.g. PathTracerSettings(samples=16, seed=3).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def clamp_indirect(self) -> float:
        """
        Light Paths > Clamp Indirect as Cycles': an indirect contribution whose components average more than this is scaled down to it; 0 = off (0).
        """
    @clamp_indirect.setter
    def clamp_indirect(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def diffuse_bounces(self) -> int:
        """
        Diffuse bounce limit (4).
        """
    @diffuse_bounces.setter
    def diffuse_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def filter_glossy(self) -> float:
        """
        Light Paths > Filter Glossy as Cycles': after a bounce whose BSDF pdf was below this value, glossy and glass lobes widen to GGX alpha sqrt(1 - pdf / value) / 2, against the caustic fireflies of mirrors seen through diffuse bounces; 0 = off (0).
        """
    @filter_glossy.setter
    def filter_glossy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def filter_width(self) -> float:
        """
        Film > Pixel Filter's width in pixels as Cycles' Filter Size, [0.01, 10] (1.0; Cycles' default 1.5): a box of width w spans w pixels, a Gaussian of width w has sigma w / 4, a Blackman-Harris of width w spans 2 w.
        """
    @filter_width.setter
    def filter_width(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_bounces(self) -> int:
        """
        Glossy bounce limit (4).
        """
    @glossy_bounces.setter
    def glossy_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def light_splits(self) -> int:
        """
        Most emitters one next-event estimate samples: the light tree's splitting, one shadow ray each (4; 1 = one emitter per shadow ray).
        """
    @light_splits.setter
    def light_splits(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def max_bounces(self) -> int:
        """
        Total bounce limit, Cycles' (12).
        """
    @max_bounces.setter
    def max_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def pixel_filter(self) -> PixelFilter:
        """
        Film > Pixel Filter as Cycles': PixelFilter BOX, GAUSSIAN or BLACKMAN_HARRIS, drawn per sample around its pixel (BOX; Cycles' default is BLACKMAN_HARRIS).
        """
    @pixel_filter.setter
    def pixel_filter(self, arg0: PixelFilter) -> None:
        ...
    @property
    def roulette_survival(self) -> RouletteSurvival:
        """
        RouletteSurvival (SQRT_THROUGHPUT: min(1, sqrt(T)), Cycles'; THROUGHPUT: min(1, T)).
        """
    @roulette_survival.setter
    def roulette_survival(self, arg0: RouletteSurvival) -> None:
        ...
    @property
    def russian_roulette_depth(self) -> int:
        """
        Surfaces before Russian roulette may end a path (3).
        """
    @russian_roulette_depth.setter
    def russian_roulette_depth(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def samples(self) -> int:
        """
        Samples per pixel rendered by render_path_traced (default 64).
        """
    @samples.setter
    def samples(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed; the image is a pure function of it (default 0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def tile_size(self) -> int:
        """
        Tile side in pixels (16).
        """
    @tile_size.setter
    def tile_size(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def transmission_bounces(self) -> int:
        """
        Transmission bounce limit (12).
        """
    @transmission_bounces.setter
    def transmission_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def world_sampling(self) -> WorldSampling:
        """
        WorldSampling (COSINE).
        """
    @world_sampling.setter
    def world_sampling(self, arg0: WorldSampling) -> None:
        ...
class PhotonBatch:
    """
    
    Photons [begin, end) of one pass of a PhotonLattice, traced apart (shgi.trace_photon_batch, on
    any machine with the same scene): the stored photons in photon order. PhotonLattice.solve_batches
    merges the batches of a pass into exactly the lattice solve() makes (shgi.farm traces them as
    tasks of a Dask cluster). Pickles as to_bytes().
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @staticmethod
    def from_bytes(data: bytes, what: str = 'bytes') -> PhotonBatch:
        """
        The batch to_bytes() made; OSError naming `what` for bytes that are not one.
        """
    def __getstate__(self) -> bytes:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, arg0: bytes) -> None:
        ...
    def to_bytes(self) -> bytes:
        """
        The batch as bytes (exact: float32 as held; 48 bytes per stored photon).
        """
    @property
    def begin(self) -> int:
        """
        Its first photon index.
        """
    @property
    def bounces(self) -> int:
        """
        Rays traced.
        """
    @property
    def emitted(self) -> int:
        """
        Photons emitted (end - begin; 0 in a scene without emitters).
        """
    @property
    def end(self) -> int:
        """
        One past its last photon index.
        """
    @property
    def pass_index(self) -> int:
        """
        The pass (0, 1, ...) it belongs to.
        """
    @property
    def photons_stored(self) -> int:
        """
        Stored photons (global and caustic).
        """
    @property
    def seconds(self) -> float:
        """
        Tracing time.
        """
    @property
    def settings(self) -> PhotonLatticeSettings:
        """
        The PhotonLatticeSettings it was traced with.
        """
class PhotonLattice(IndirectField, GiSolver):
    """
    
    The ISLLPM solver (seed 000): photons traced from the lights, injected into SH lattices.
    
    Interactive: call refine() repeatedly; each call traces `photons` more and the lattices
    average all passes. Non-interactive: one refine() with many photons, then render any camera.
    After editing and re-committing the scene, call reset().
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @staticmethod
    def load(path: str | bytes | os.PathLike) -> PhotonLattice:
        """
        A PhotonLattice read from save()'s file: it renders and reports as the saved one, but has no scene, so refine() and reset() raise ValueError (OSError naming a bad file).
        """
    def __init__(self, scene: Scene, settings: PhotonLatticeSettings = ..., progress: Progress = None) -> None:
        """
        Measures the surface inside the lattices' cells (the scene must be committed).
        """
    def current_field(self) -> typing.Any:
        """
        The lattice itself: it is its own IndirectField (not to be read while a pass runs).
        """
    def refine(self, progress: Progress = None) -> None:
        """
        Traces one more pass of photons and rebuilds the lattices (GIL released). Raises shgi.Cancelled on cancel, keeping the previous solution.
        """
    def reset(self, progress: Progress = None) -> None:
        """
        Forgets every pass and re-measures the (re-committed) scene.
        """
    def save(self, path: str | bytes | os.PathLike) -> None:
        """
        Writes the solved lattices, their settings, caustic photons and timings to a binary file (float32 as held, so load() looks up the same light; OSError naming a path that cannot be written).
        """
    def solve(self, progress: Progress = None) -> None:
        """
        The same as refine().
        """
    def solve_batches(self, batches: collections.abc.Sequence[PhotonBatch], progress: Progress = None) -> None:
        """
        The next pass from PhotonBatch objects traced apart (shgi.trace_photon_batch) that together cover its photons [0, settings.photons), in any order: the lattice then equals the one solve() makes, bit for bit (GIL released). ValueError, changing nothing, for a batch with other settings, of another pass, or ranges with gaps or overlaps; shgi.Cancelled keeps the previous solution.
        """
    @property
    def lattices(self) -> dict:
        """
        The solved (averaged, blurred) lattices as {'global': ..., 'caustic': ...}, each a dict: origin (x, y, z) of the lower corner (m), cell_size (m), dims (nx, ny, nz), order, sh: float32 array (nz, ny, nx, coefficients, 3) of incident radiance (W m^-2 sr^-1, index l(l+1)+m, no Condon-Shortley phase), cell (i, j, k) centred at origin + (i + 0.5, j + 0.5, k + 0.5) cell_size.
        """
    @property
    def memory_bytes(self) -> int:
        """
        Bytes held by the lattices and photon map.
        """
    @property
    def passes(self) -> int:
        """
        Solve passes averaged so far.
        """
    @property
    def settings(self) -> PhotonLatticeSettings:
        """
        A copy of the settings.
        """
    @property
    def stage_seconds(self) -> list:
        """
        [(stage, seconds)] of the last pass.
        """
    @property
    def timings(self) -> dict:
        """
        The last solve: seconds of emit_trace, injection, blur; photons_emitted, photons_stored, bounces.
        """
class PhotonLatticeSettings:
    """
    Settings of the PhotonLattice solver; every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        PhotonLatticeSettings(**fields), e.g. PhotonLatticeSettings(photons=100000).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def blur_passes(self) -> int:
        """
        3x3x3 blurs of the global lattice (0: blurring darkens corners).
        """
    @blur_passes.setter
    def blur_passes(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def bounds_max(self) -> tuple:
        """
        Upper corner (m) when use_bounds.
        """
    @bounds_max.setter
    def bounds_max(self, arg1: typing.Any) -> None:
        ...
    @property
    def bounds_min(self) -> tuple:
        """
        Lower corner (m) when use_bounds.
        """
    @bounds_min.setter
    def bounds_min(self, arg1: typing.Any) -> None:
        ...
    @property
    def caustic_blur_passes(self) -> int:
        """
        3x3x3 blurs of the caustic lattice (0).
        """
    @caustic_blur_passes.setter
    def caustic_blur_passes(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def caustic_neighbours(self) -> int:
        """
        Photons per density estimate, PHOTON_MAP mode (50).
        """
    @caustic_neighbours.setter
    def caustic_neighbours(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def caustic_order(self) -> int:
        """
        Caustic lattice SH order (1).
        """
    @caustic_order.setter
    def caustic_order(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def caustic_radius(self) -> float:
        """
        Max radius (m) of the density estimate; 0 = 2% of the bounds' diagonal.
        """
    @caustic_radius.setter
    def caustic_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def caustic_resolution(self) -> int:
        """
        Caustic lattice: cells along the longest side (64).
        """
    @caustic_resolution.setter
    def caustic_resolution(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def caustics(self) -> CausticMode:
        """
        CausticMode (LATTICE).
        """
    @caustics.setter
    def caustics(self, arg0: CausticMode) -> None:
        ...
    @property
    def glossy_bounces(self) -> int:
        """
        Photon glossy scatterings, a budget apart from max_bounces as Cycles' Glossy bounces (4); -1: counted against max_bounces.
        """
    @glossy_bounces.setter
    def glossy_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def interpolation(self) -> LatticeInterpolation:
        """
        LatticeInterpolation (CUBIC).
        """
    @interpolation.setter
    def interpolation(self, arg0: LatticeInterpolation) -> None:
        ...
    @property
    def max_bounces(self) -> int:
        """
        Photon scatterings after emission; 4 matches Cycles' default diffuse bounces (4).
        """
    @max_bounces.setter
    def max_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def normal_offset(self) -> float:
        """
        Cells along the normal before sampling, against self-lighting (0.25).
        """
    @normal_offset.setter
    def normal_offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def order(self) -> int:
        """
        Global lattice SH order, 1 or 2 (2).
        """
    @order.setter
    def order(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def photons(self) -> int:
        """
        Photons emitted per solve() (200000).
        """
    @photons.setter
    def photons(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def resolution(self) -> int:
        """
        Global lattice: cells along the bounds' longest side (16).
        """
    @resolution.setter
    def resolution(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def specular_roughness(self) -> float:
        """
        Lobes up to this roughness make caustic paths (0.1).
        """
    @specular_roughness.setter
    def specular_roughness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def use_bounds(self) -> bool:
        """
        Use bounds_min/bounds_max instead of the scene's bounds (False).
        """
    @use_bounds.setter
    def use_bounds(self, arg0: bool) -> None:
        ...
    @property
    def world_in_field(self) -> bool:
        """
        The lattices carry the world's direct light; renderers skip the world in next-event estimation; that light then lands in the Ind passes (False).
        """
    @world_in_field.setter
    def world_in_field(self, arg0: bool) -> None:
        ...
class PixelFilter:
    """
    Film > Pixel Filter as Cycles' (its Type).
    
    Members:
    
      BOX
    
      GAUSSIAN
    
      BLACKMAN_HARRIS
    """
    BLACKMAN_HARRIS: typing.ClassVar[PixelFilter]  # value = <PixelFilter.BLACKMAN_HARRIS: 2>
    BOX: typing.ClassVar[PixelFilter]  # value = <PixelFilter.BOX: 0>
    GAUSSIAN: typing.ClassVar[PixelFilter]  # value = <PixelFilter.GAUSSIAN: 1>
    __members__: typing.ClassVar[dict[str, PixelFilter]]  # value = {'BOX': <PixelFilter.BOX: 0>, 'GAUSSIAN': <PixelFilter.GAUSSIAN: 1>, 'BLACKMAN_HARRIS': <PixelFilter.BLACKMAN_HARRIS: 2>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: PixelFilter) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: PixelFilter) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class PreviewRenderer:
    """
    
    Progressive preview frames: exact direct light, indirect light from an IndirectField.
    
    render(field, samples) adds samples; passes() returns the passes (as the path tracer's);
    timings is the last render's stage times in seconds (primary, direct, indirect, total).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, scene: Scene, settings: PreviewSettings = ..., camera: Camera = None) -> None:
        """
        camera: a shgi.Camera replacing the scene's (any view of a solved field).
        """
    def passes(self, names: typing.Any = None) -> dict:
        """
        {pass name: float32 array (H, W, C)}, as PathTracer.passes(): every pass the renderer sums (only Combined with settings.combined_only), or those in `names`.
        """
    def render(self, field: IndirectField, samples: typing.Any = None, progress: Progress = None) -> None:
        """
        Adds `samples` samples per pixel (default 1) lit indirectly by `field` (None: direct light only). The field must have been solved on the renderer's scene.
        """
    @property
    def timings(self) -> dict:
        """
        Seconds of the last render: primary, direct, indirect, total.
        """
class PreviewSettings:
    """
    Settings of the preview renderer; every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        PreviewSettings(**fields), e.g. PreviewSettings(samples=4, seed=1).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def clamp_indirect(self) -> float:
        """
        Light Paths > Clamp Indirect as Cycles': an indirect contribution whose components average more than this is scaled down to it; 0 = off (0).
        """
    @clamp_indirect.setter
    def clamp_indirect(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def combined_only(self) -> bool:
        """
        Sum only the Combined pass (False): what a viewport shows, without the other 13 passes' film traffic.
        """
    @combined_only.setter
    def combined_only(self, arg0: bool) -> None:
        ...
    @property
    def filter_glossy(self) -> float:
        """
        Light Paths > Filter Glossy as Cycles': after a bounce whose BSDF pdf was below this value, glossy and glass lobes widen to GGX alpha sqrt(1 - pdf / value) / 2, against the caustic fireflies of mirrors seen through diffuse bounces; 0 = off (0).
        """
    @filter_glossy.setter
    def filter_glossy(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def filter_width(self) -> float:
        """
        Film > Pixel Filter's width in pixels as Cycles' Filter Size, [0.01, 10] (1.0; Cycles' default 1.5): a box of width w spans w pixels, a Gaussian of width w has sigma w / 4, a Blackman-Harris of width w spans 2 w.
        """
    @filter_width.setter
    def filter_width(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def final_gather(self) -> bool:
        """
        Final gather (False): the first surface sends one BSDF-sampled ray per sample and the field is read where it lands after a diffuse bounce (a glossy one goes on as a reference path), so the field's blocks and leaks reach the picture only through one more bounce.
        """
    @final_gather.setter
    def final_gather(self, arg0: bool) -> None:
        ...
    @property
    def light_splits(self) -> int:
        """
        Most emitters one next-event estimate samples, as PathTracerSettings.light_splits (4).
        """
    @light_splits.setter
    def light_splits(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def max_specular_bounces(self) -> int:
        """
        Mirror/glass bounces followed per path (8).
        """
    @max_specular_bounces.setter
    def max_specular_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def pixel_filter(self) -> PixelFilter:
        """
        Film > Pixel Filter as Cycles': PixelFilter BOX, GAUSSIAN or BLACKMAN_HARRIS, drawn per sample around its pixel (BOX; Cycles' default is BLACKMAN_HARRIS).
        """
    @pixel_filter.setter
    def pixel_filter(self, arg0: PixelFilter) -> None:
        ...
    @property
    def reuse_field_lookups(self) -> bool:
        """
        Share one field lookup among the pixels of a 2 x 2 quad whose first surfaces lie within the field's reuse distance and whose normals agree (True); False: one lookup per pixel.
        """
    @reuse_field_lookups.setter
    def reuse_field_lookups(self, arg0: bool) -> None:
        ...
    @property
    def samples(self) -> int:
        """
        Samples per pixel rendered by render_preview (default 16).
        """
    @samples.setter
    def samples(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (default 0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def tile_size(self) -> int:
        """
        Tile side in pixels (16), rounded up to an even number.
        """
    @tile_size.setter
    def tile_size(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def world_sampling(self) -> WorldSampling:
        """
        WorldSampling (COSINE).
        """
    @world_sampling.setter
    def world_sampling(self, arg0: WorldSampling) -> None:
        ...
class PrincipledModel:
    """
    How a Material's closures combine, as each Blender's Cycles.
    
    Members:
    
      V1 : Blender 3.x: diffuse and specular added
    
      V2 : Blender 4.0+: the specular layer dims the diffuse by its albedo; Glossy Color holds that albedo
    """
    V1: typing.ClassVar[PrincipledModel]  # value = <PrincipledModel.V1: 0>
    V2: typing.ClassVar[PrincipledModel]  # value = <PrincipledModel.V2: 1>
    __members__: typing.ClassVar[dict[str, PrincipledModel]]  # value = {'V1': <PrincipledModel.V1: 0>, 'V2': <PrincipledModel.V2: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: PrincipledModel) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: PrincipledModel) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class ProbeField(IndirectField):
    """
    
    An immutable snapshot of SH probes, read as an IndirectField (render_preview, PreviewRenderer).
    From ProbeGrid.field(), ProbeField.load(path) or ProbeField.import_exr(json_path).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @staticmethod
    def import_exr(json_path: str | bytes | os.PathLike, lookup: ProbeLookupSettings = ...) -> ProbeField:
        """
        Reads an EXR + JSON export written by export().
        """
    @staticmethod
    def load(path: str | bytes | os.PathLike, lookup: ProbeLookupSettings = ...) -> ProbeField:
        """
        Reads a binary cache written by save() (OSError naming a bad file).
        """
    def export(self, json_path: str | bytes | os.PathLike) -> None:
        """
        Writes <stem>.json and per volume <stem>_volume<v>.exr (float SH, positions, active, variance) and <stem>_volume<v>_visibility.exr; the JSON states basis, units and layout.
        """
    def save(self, path: str | bytes | os.PathLike) -> None:
        """
        Writes the compact binary cache (SH at half precision: 56 bytes per L2 probe).
        """
    def splice(self, brick: ProbeField, first: typing.SupportsIndex, count: typing.SupportsIndex) -> ProbeField:
        """
        These probes with probes first .. first + count - 1 (their SH, variance and visibility) taken from `brick`, the same grid after the same passes whose probes there were updated apart (ProbeGrid.update_probes): the merge of a solve split into bricks. ValueError names the first difference between the two grids.
        """
    def with_lookup(self, lookup: ProbeLookupSettings) -> ProbeField:
        """
        The same probes read with other lookup settings.
        """
    @property
    def active(self) -> numpy.typing.NDArray[numpy.bool]:
        """
        (N,) bool: False for probes inside geometry (never updated or read).
        """
    @property
    def order(self) -> int:
        """
        SH order of the probes (1..4).
        """
    @property
    def passes(self) -> int:
        """
        Update passes blended into these probes.
        """
    @property
    def positions(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, 3) float32 probe positions after relocation (m, world).
        """
    @property
    def probe_count(self) -> int:
        """
        Probes in all volumes (active or not).
        """
    @property
    def sh(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, coefficients, 3) float32 incident radiance SH per probe (W m^-2 sr^-1), index l(l+1)+m, no Condon-Shortley phase.
        """
    @property
    def variance(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N,) float32 variance of each probe's DC luminance estimate.
        """
    @property
    def volumes(self) -> list[ProbeVolume]:
        """
        The ProbeVolumes, in probe order.
        """
class ProbeGrid(IndirectField, GiSolver):
    """
    
    SH probe grids updated by path tracing (seed 002), with DDGI-style relocation and visibility.
    
    Each refine() (or update(), its older name) traces rays_per_probe paths per active probe and blends them into the probes
    (running mean, then an exponential blend with `hysteresis`). field() returns a snapshot for
    rendering that later updates leave untouched. After editing and re-committing the scene, call
    reset().
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @staticmethod
    def from_field(scene: Scene, settings: ProbeGridSettings, field: ProbeField) -> ProbeGrid:
        """
        Continues refining stored probes (their volumes and order replace the settings').
        """
    def __init__(self, scene: Scene, settings: ProbeGridSettings = ..., progress: Progress = None) -> None:
        """
        Places the probes (the scene must be committed).
        """
    def current_field(self) -> ProbeField:
        """
        The same as field().
        """
    def export(self, json_path: str | bytes | os.PathLike) -> None:
        """
        Writes <stem>.json and per volume <stem>_volume<v>.exr (float SH, positions, active, variance) and <stem>_volume<v>_visibility.exr; the JSON states basis, units and layout.
        """
    def field(self) -> ProbeField:
        """
        An immutable ProbeField of the current probes (safe to render while refine() runs on another thread).
        """
    def refine(self, progress: Progress = None) -> None:
        """
        One update pass (GIL released). Raises shgi.Cancelled on cancel, keeping the previous probes.
        """
    def relative_error(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N,) sqrt(variance) / DC luminance per probe (inf before the first update).
        """
    def reset(self, progress: Progress = None) -> None:
        """
        Forgets every pass and re-places the probes.
        """
    def save(self, path: str | bytes | os.PathLike) -> None:
        """
        Writes the compact binary cache (SH at half precision: 56 bytes per L2 probe).
        """
    def update(self, progress: Progress = None) -> None:
        """
        The same as refine().
        """
    def update_probes(self, first: typing.SupportsIndex, count: typing.SupportsIndex, progress: Progress = None) -> None:
        """
        One update pass over probes first .. first + count - 1 only (a brick of a solve split over machines); the others keep their state, the pass counts. Bricks updated apart and merged with ProbeField.splice equal update() bit for bit.
        """
    @property
    def active(self) -> numpy.typing.NDArray[numpy.bool]:
        """
        (N,) bool: False for probes inside geometry (never updated or read).
        """
    @property
    def active_count(self) -> int:
        """
        Probes outside geometry.
        """
    @property
    def memory_bytes(self) -> int:
        """
        Bytes held by the probes.
        """
    @property
    def order(self) -> int:
        """
        SH order of the probes (1..4).
        """
    @property
    def passes(self) -> int:
        """
        Update passes blended in.
        """
    @property
    def positions(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, 3) float32 probe positions after relocation (m, world).
        """
    @property
    def probe_count(self) -> int:
        """
        Probes in all volumes (active or not).
        """
    @property
    def settings(self) -> ProbeGridSettings:
        """
        A copy of the settings.
        """
    @property
    def sh(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N, coefficients, 3) float32 incident radiance SH per probe (W m^-2 sr^-1), index l(l+1)+m, no Condon-Shortley phase.
        """
    @property
    def stage_seconds(self) -> list:
        """
        [(stage, seconds)] of the last placement and pass.
        """
    @property
    def timings(self) -> dict:
        """
        Seconds of the last placement and update; paths (and rays) of the last update.
        """
    @property
    def variance(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (N,) float32 variance of each probe's DC luminance estimate.
        """
    @property
    def volumes(self) -> list[ProbeVolume]:
        """
        The ProbeVolumes, in probe order.
        """
class ProbeGridSettings:
    """
    Settings of the ProbeGrid solver; every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        ProbeGridSettings(**fields), e.g. ProbeGridSettings(order=1).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def backface_threshold(self) -> float:
        """
        Share of back-face hits marking a probe as inside geometry (0.25).
        """
    @backface_threshold.setter
    def backface_threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def bleed_bias(self) -> float:
        """
        Chebyshev cut-off (0; EEVEE's Bleed Bias).
        """
    @bleed_bias.setter
    def bleed_bias(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def bounces(self) -> int:
        """
        Diffuse and glossy scatterings along a probe path (3: with the renderer's surface, Cycles' default 4).
        """
    @bounces.setter
    def bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def clamp(self) -> float:
        """
        A radiance sample whose components average more than this is scaled down to it (Light Paths > Clamp Indirect, as Cycles clamps); 0 = off (0).
        """
    @clamp.setter
    def clamp(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def hysteresis(self) -> float:
        """
        History weight of the exponential blend, in [0, 1) (0.95).
        """
    @hysteresis.setter
    def hysteresis(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def include_direct(self) -> bool:
        """
        Keep emitters and world seen straight from the probes (False).
        """
    @include_direct.setter
    def include_direct(self, arg0: bool) -> None:
        ...
    @property
    def light_splits(self) -> int:
        """
        Most emitters one next-event estimate on a probe path samples, as PathTracerSettings.light_splits (4).
        """
    @light_splits.setter
    def light_splits(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def max_offset(self) -> float:
        """
        Largest relocation, in probe spacings per axis (0.45).
        """
    @max_offset.setter
    def max_offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_bias(self) -> float:
        """
        Probe spacings along the surface's interpolated normal (0.25; EEVEE's Bias).
        """
    @normal_bias.setter
    def normal_bias(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def order(self) -> int:
        """
        SH order of the probes, 1..4 (2).
        """
    @order.setter
    def order(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def placement_rays(self) -> int:
        """
        Rays per probe for placement (128).
        """
    @placement_rays.setter
    def placement_rays(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def rays_per_probe(self) -> int:
        """
        Paths per probe per update (256).
        """
    @rays_per_probe.setter
    def rays_per_probe(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def relocate(self) -> bool:
        """
        Move probes out of geometry before disabling them (True).
        """
    @relocate.setter
    def relocate(self, arg0: bool) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def spacing(self) -> float:
        """
        Probe spacing (m) of the fitted volume; 0 = longest side / 8.
        """
    @spacing.setter
    def spacing(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def view_bias(self) -> float:
        """
        Probe spacings towards the viewer (0; DDGI's view bias).
        """
    @view_bias.setter
    def view_bias(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def visibility(self) -> bool:
        """
        Leak prevention weights (True).
        """
    @visibility.setter
    def visibility(self, arg0: bool) -> None:
        ...
    @property
    def visibility_blur(self) -> float:
        """
        Angular radius (rad) of the distance filter (0.10; EEVEE's Blur).
        """
    @visibility_blur.setter
    def visibility_blur(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def visibility_resolution(self) -> int:
        """
        Octahedral visibility texels per side per probe (8).
        """
    @visibility_resolution.setter
    def visibility_resolution(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def volumes(self) -> list[ProbeVolume]:
        """
        List of ProbeVolume; empty: one volume fitted to the scene bounds.
        """
    @volumes.setter
    def volumes(self, arg0: collections.abc.Sequence[ProbeVolume]) -> None:
        ...
class ProbeLookupSettings:
    """
    How shading points read probes (EEVEE: Bias, Bleed Bias).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        ProbeLookupSettings(**fields).
        """
    @property
    def bleed_bias(self) -> float:
        """
        Chebyshev weights below it become 0, against light bleeding (0).
        """
    @bleed_bias.setter
    def bleed_bias(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_bias(self) -> float:
        """
        Probe spacings the shading point moves along its normal (0.25).
        """
    @normal_bias.setter
    def normal_bias(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def view_bias(self) -> float:
        """
        Probe spacings the shading point moves towards the viewer (0).
        """
    @view_bias.setter
    def view_bias(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def visibility(self) -> bool:
        """
        Back-face and Chebyshev visibility weights; False = plain trilinear (True).
        """
    @visibility.setter
    def visibility(self, arg0: bool) -> None:
        ...
class ProbeVolume:
    """
    
    A box of probes: the cube [-1, 1]^3 of world_from_volume (like Blender's irradiance volume
    object), with resolution probes along each local axis at the cell centres.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        ProbeVolume(world_from_volume=4x4, resolution=(nx, ny, nz)).
        """
    def __repr__(self) -> str:
        ...
    @property
    def resolution(self) -> tuple[int, int, int]:
        """
        Probes along the local x, y, z axes, each >= 1.
        """
    @resolution.setter
    def resolution(self, arg1: collections.abc.Sequence) -> None:
        ...
    @property
    def world_from_volume(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        4x4 matrix (row-major, Blender's matrix_world) mapping [-1,1]^3 to the world.
        """
    @world_from_volume.setter
    def world_from_volume(self, arg1: typing.Any) -> None:
        ...
class Progress:
    """
    
    Progress and cancellation of a long operation.
    
    Pass one to any long call (``progress=``). ``cancel()`` from another thread makes the call stop
    within one chunk of work and raise ``shgi.Cancelled``. The optional ``callback(fraction, stage)``
    is called at most every ``min_interval`` seconds, possibly from a worker thread.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, callback: collections.abc.Callable | None = None, min_interval: typing.SupportsFloat | typing.SupportsIndex = 0.05) -> None:
        """
        Creates a Progress; callback(fraction: float, stage: str) is optional.
        """
    def cancel(self) -> None:
        """
        Asks the operation to stop as soon as possible.
        """
    @property
    def cancelled(self) -> bool:
        """
        True once cancel() was called.
        """
    @property
    def fraction(self) -> float:
        """
        Fraction of the work done, in [0, 1].
        """
    @property
    def stage(self) -> str:
        """
        Name of the current stage.
        """
class PropagationField(IndirectField):
    """
    An immutable light propagation volume as an IndirectField (its accumulated light).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @staticmethod
    def load(path: str) -> PropagationField:
        """
        The field a save() wrote; OSError naming the file when it is not one.
        """
    def level_field(self, level: typing.SupportsIndex) -> PropagationField:
        """
        Cascade level `level` alone (0 the finest) as a field of its own, unblended.
        """
    def save(self, path: str) -> None:
        """
        Writes the field to an SHGI .shlpv file (atomically); load() reads it back.
        """
    @property
    def level_count(self) -> int:
        """
        Cascade levels (1 without cascades; 0 before the first pass), the finest first.
        """
    @property
    def memory_bytes(self) -> int:
        """
        Bytes of its volumes.
        """
class PropagationSettings:
    """
    Settings of the PropagationVolume solver (light propagation volumes); every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        PropagationSettings(**fields), e.g. PropagationSettings(order=1, steps=16).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def cascade_center(self) -> tuple:
        """
        The point the finer cascade levels are centred on without the camera (cascade_follow_camera off, or a scene without one): a point of interest for a bake ((0, 0, 0)).
        """
    @cascade_center.setter
    def cascade_center(self, arg1: typing.Any) -> None:
        ...
    @property
    def cascade_follow_camera(self) -> bool:
        """
        Centre the finer cascade levels on the scene's camera (its position when the volume is reset) when the scene has one (True).
        """
    @cascade_follow_camera.setter
    def cascade_follow_camera(self, arg0: bool) -> None:
        ...
    @property
    def cascades(self) -> int:
        """
        Nested volumes around cascade_center, each finer level with half the cells' size and `resolution` cells per axis; 1: one volume over the scene (1).
        """
    @cascades.setter
    def cascades(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def clamp_at_surfaces(self) -> bool:
        """
        With unclamped_transfer: clamp the lobes of the cells whose light a wall stops in part, linear elsewhere, so that walls neither make light nor return what goes into them; no effect without unclamped_transfer (True).
        """
    @clamp_at_surfaces.setter
    def clamp_at_surfaces(self, arg0: bool) -> None:
        ...
    @property
    def clamp_per_transfer(self) -> bool:
        """
        HOLPV (order 2) only, with clamp_at_surfaces: clamp only the transfers a wall stops in part, not every transfer of such a cell, so that the higher-order lobes keep their light at a room's edges; the LPV ignores it (True).
        """
    @clamp_per_transfer.setter
    def clamp_per_transfer(self, arg0: bool) -> None:
        ...
    @property
    def damping(self) -> bool:
        """
        Damp the lookup where the light arriving against the normal is stronger half a cell behind the lookup point than in front of it (seed 003 §3.2.4's directional derivative, against self-lighting and bleeding) (True).
        """
    @damping.setter
    def damping(self, arg0: bool) -> None:
        ...
    @property
    def distance(self) -> float:
        """
        How far the light travels, in cells, when steps is 0: each order takes the steps its stencil needs to carry light this far (the LPV's steps move light 0.915 cells, the HOLPV's 1.415) (32.0).
        """
    @distance.setter
    def distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def drop_outward_vpls(self) -> bool:
        """
        Drop the VPLs that light nothing: on the scene's bounds facing out (a sunlit roof or outer wall), whose light otherwise reaches the interior through the cells their surface runs through (True).
        """
    @drop_outward_vpls.setter
    def drop_outward_vpls(self, arg0: bool) -> None:
        ...
    @property
    def extend_to_bounds(self) -> bool:
        """
        Give the cells whose centres lie outside the scene's bounds the light of the inside cell next to them, against a dark strip along the edges of rooms whose walls are the bounds; not the default: the HOLPV's two rooms then read 1.12x the path tracer (docs/methods.md) (False).
        """
    @extend_to_bounds.setter
    def extend_to_bounds(self, arg0: bool) -> None:
        ...
    @property
    def furnace_scale(self) -> bool:
        """
        Scale the light to what a closed room reads once its light has settled (the furnace, an exact answer) instead of a single VPL's near field: divided by the furnace's reading of the transfer, 1.22-1.37; needs travel_reinjection (False).
        """
    @furnace_scale.setter
    def furnace_scale(self, arg0: bool) -> None:
        ...
    @property
    def glossy_bounces(self) -> int:
        """
        Glossy scatterings of a light path, a budget of their own beside vpl_bounces, -1..64; -1: they count against vpl_bounces (-1).
        """
    @glossy_bounces.setter
    def glossy_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_vpls(self) -> bool:
        """
        A VPL's surface scatters with its rough glossy lobes too, as if diffuse; False: its diffuse lobe only, and the volume misses the light a glossy layer reflects onto other surfaces (False).
        """
    @glossy_vpls.setter
    def glossy_vpls(self, arg0: bool) -> None:
        ...
    @property
    def light_share_uniform(self) -> float:
        """
        Share of the photons spread evenly over the lamps (a light, an emissive object, the world), the rest by flux; each photon's power is divided by its probability, so the light stays unbiased; 0..1 (0.5).
        """
    @light_share_uniform.setter
    def light_share_uniform(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def normal_offset(self) -> float:
        """
        Cells along the surface's interpolated normal before the lookup, against self-lighting and leaks through walls (1.0).
        """
    @normal_offset.setter
    def normal_offset(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def occlude_first_step(self) -> bool:
        """
        Geometry volume blocking on the first step too (the seed skips it): keeps the light of VPLs next to a thin wall from crossing it (True).
        """
    @occlude_first_step.setter
    def occlude_first_step(self, arg0: bool) -> None:
        ...
    @property
    def occlusion(self) -> bool:
        """
        Geometry volume blocking from the second step on, or the first with occlude_first_step (True).
        """
    @occlusion.setter
    def occlusion(self, arg0: bool) -> None:
        ...
    @property
    def order(self) -> int:
        """
        1: LPV (L1 SH, 6 directions); 2: HOLPV (L2 SH, 26 directions) (2).
        """
    @order.setter
    def order(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def photons(self) -> int:
        """
        Light paths traced per pass; their surface hits are the VPLs (100000).
        """
    @photons.setter
    def photons(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def resolution(self) -> int:
        """
        Cells along the longest side of the scene (32).
        """
    @resolution.setter
    def resolution(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def settle_fraction(self) -> float:
        """
        Stop propagating once the light in flight is at most this fraction of the injected light (the accumulation has settled); steps or distance are then the most it takes; 0: off (0.0).
        """
    @settle_fraction.setter
    def settle_fraction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def steps(self) -> int:
        """
        Propagation steps; 0 takes them from distance (0).
        """
    @steps.setter
    def steps(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def travel_reinjection(self) -> bool:
        """
        Re-inject the light crossing each face along its travel direction (keeps its momentum: less diffusion, converges in fewer steps) instead of as a cosine lobe along the face's normal (the seed) (True).
        """
    @travel_reinjection.setter
    def travel_reinjection(self, arg0: bool) -> None:
        ...
    @property
    def unclamped_transfer(self) -> bool:
        """
        Propagate the lobes unclamped (a linear transfer per neighbour offset) instead of clamping each source lobe at zero and rescaling it to its flux (True).
        """
    @unclamped_transfer.setter
    def unclamped_transfer(self, arg0: bool) -> None:
        ...
    @property
    def vpl_bounces(self) -> int:
        """
        Surface hits per light path that become VPLs: 1 is the published single bounce, n gives n bounces of indirect light (4).
        """
    @vpl_bounces.setter
    def vpl_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def windowed_reinjection(self) -> bool:
        """
        With travel_reinjection and order 2: scale the re-injected beam's band 2 by 4/5 so that its light does not come back onto the surface it left (the HOLPV's self-lighting at bright surfaces; docs/methods.md) (True).
        """
    @windowed_reinjection.setter
    def windowed_reinjection(self, arg0: bool) -> None:
        ...
class PropagationVolume(GiSolver):
    """
    
    Light propagation volumes (seed 003): VPLs from traced light paths, injected as cosine lobes
    into an SH grid and propagated step by step (LPV: 6 directions, L1; HOLPV: 26 directions, L2).
    
    Each refine() traces `photons` more light paths and propagates the mean of every pass's VPLs.
    current_field() is an immutable snapshot. After editing and re-committing the scene, call
    reset().
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @staticmethod
    def estimate_memory_bytes(scene: Scene, settings: PropagationSettings) -> int:
        """
        Bytes the volumes and transmittances of these settings take for the scene (all cascade levels), before anything is allocated; ValueError for bad settings.
        """
    def __init__(self, scene: Scene, settings: PropagationSettings = ..., progress: Progress = None) -> None:
        """
        Builds the geometry volume (the scene must be committed).
        """
    def current_field(self) -> PropagationField:
        """
        The PropagationField of the last pass (safe to render while refine() runs).
        """
    def recenter(self, point: typing.Any, progress: Progress = None) -> list[int]:
        """
        Cascades that follow a moving camera: moves every finer level whose inner region (the middle half of its box per axis) no longer holds `point` to be centred on it (snapped to its cells, inside the scene) and rebuilds those levels alone: geometry, every pass's VPLs traced again, propagation (GIL released) - the field a volume reset there gives after as many passes. Returns the levels moved, finest first ([] without cascades). Raises shgi.Cancelled on cancel, keeping the volume as it was; ValueError for a point that is not finite.
        """
    def refine(self, progress: Progress = None) -> None:
        """
        One pass: traces VPLs, injects, propagates (GIL released). Raises shgi.Cancelled on cancel, keeping the previous field.
        """
    def reset(self, progress: Progress = None) -> None:
        """
        Forgets every pass and rebuilds the geometry volume of the (re-committed) scene.
        """
    @property
    def memory_bytes(self) -> int:
        """
        Bytes held by the volumes.
        """
    @property
    def passes(self) -> int:
        """
        Passes averaged so far.
        """
    @property
    def settings(self) -> PropagationSettings:
        """
        A copy of the settings.
        """
    @property
    def stage_seconds(self) -> list:
        """
        [(stage, seconds)] of the last pass: vpl_trace, vpl_reflect, injection, geometry_volume (of the last reset), propagation_step_1 ... N; with cascades, the last four per level prefixed level_<l>_ (0 the finest).
        """
    @property
    def vpl_count(self) -> int:
        """
        VPLs injected by the last pass.
        """
class RadianceField(IndirectField, GiSolver):
    """
    
    The radiance-field solver (seed 001): photons on a face radiance grid, SH field by gather rays.
    
    Each refine() traces `photons` more, adds their reflected flux to the grid and gathers the SH
    field again (the field is the mean of all passes). After editing and re-committing the scene,
    call reset().
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, scene: Scene, settings: RadianceFieldSettings = ..., progress: Progress = None) -> None:
        """
        Voxelises the scene: cells, their surfaces and sample points (the scene must be committed).
        """
    def current_field(self) -> typing.Any:
        """
        The solver itself: it is its own IndirectField (not to be read while a pass runs).
        """
    def refine(self, progress: Progress = None) -> None:
        """
        Traces one more pass of photons, updates the radiance grid and gathers the SH field (GIL released). Raises shgi.Cancelled on cancel, keeping the previous solution.
        """
    def reset(self, progress: Progress = None) -> None:
        """
        Forgets every pass and voxelises the (re-committed) scene again.
        """
    @property
    def memory_bytes(self) -> int:
        """
        Bytes held by the grids and the SH field.
        """
    @property
    def passes(self) -> int:
        """
        Passes averaged so far.
        """
    @property
    def settings(self) -> RadianceFieldSettings:
        """
        A copy of the settings.
        """
    @property
    def stage_seconds(self) -> list:
        """
        [(stage, seconds)] of the last pass.
        """
    @property
    def timings(self) -> dict:
        """
        The last pass: seconds of voxelise (construction/reset), photons, radiance_grid, sh_field; photons_emitted, hits, sample_points, gather_rays.
        """
class RadianceFieldSettings:
    """
    Settings of the RadianceField solver; every field has a default.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        RadianceFieldSettings(**fields), e.g. RadianceFieldSettings(gather_rays=200).
        """
    def validate(self) -> None:
        """
        Raises ValueError naming the first invalid field.
        """
    @property
    def backface_threshold(self) -> float:
        """
        Share of gather rays seeing back faces of closed meshes that marks a sample point inside geometry (0.25).
        """
    @backface_threshold.setter
    def backface_threshold(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def bounds_max(self) -> tuple:
        """
        Upper corner (m) when use_bounds.
        """
    @bounds_max.setter
    def bounds_max(self, arg1: typing.Any) -> None:
        ...
    @property
    def bounds_min(self) -> tuple:
        """
        Lower corner (m) when use_bounds.
        """
    @bounds_min.setter
    def bounds_min(self, arg1: typing.Any) -> None:
        ...
    @property
    def diffuse_gather_rays(self) -> int:
        """
        Directions N_d of the diffuse Monte Carlo gather (32, the paper's).
        """
    @diffuse_gather_rays.setter
    def diffuse_gather_rays(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def face_estimator(self) -> FaceEstimator:
        """
        FaceEstimator: PROJECTED_AREA (exact for lit planes) or the paper's PAPER.
        """
    @face_estimator.setter
    def face_estimator(self, arg0: FaceEstimator) -> None:
        ...
    @property
    def face_sigma(self) -> float:
        """
        Standard deviation (rad) of the Gaussian weights of a hit cell's faces (0.5).
        """
    @face_sigma.setter
    def face_sigma(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def gather_rays(self) -> int:
        """
        Gather rays per sample point and pass, N_sh (400, the paper's).
        """
    @gather_rays.setter
    def gather_rays(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_bounces(self) -> int:
        """
        Photons' glossy scatterings, a budget of their own beside max_bounces, 0..64; 4 matches Cycles' default glossy bounces.
        """
    @glossy_bounces.setter
    def glossy_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_gather_rays(self) -> int:
        """
        Directions N_g of the glossy (Phong-lobe) Monte Carlo gather (64, the paper's).
        """
    @glossy_gather_rays.setter
    def glossy_gather_rays(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def glossy_in_grid(self) -> bool:
        """
        Rough glossy reflection enters the radiance grid as if diffuse (the paper's holds diffuse only) (True).
        """
    @glossy_in_grid.setter
    def glossy_in_grid(self, arg0: bool) -> None:
        ...
    @property
    def max_bounces(self) -> int:
        """
        Photon scatterings after emission; 4 matches Cycles' default diffuse bounces.
        """
    @max_bounces.setter
    def max_bounces(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def min_footprint_cosine(self) -> float:
        """
        Floor of cos(beta) in a ray's footprint 4 pi d^2 / (N cos beta) (0.1).
        """
    @min_footprint_cosine.setter
    def min_footprint_cosine(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def mip_levels(self) -> int:
        """
        Levels of the radiance grid's mip chain, the finest included (4).
        """
    @mip_levels.setter
    def mip_levels(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def monte_carlo_gathers(self) -> bool:
        """
        Irradiance and glossy light by the paper's Monte Carlo gathers of the SH (diffuse_gather_rays, glossy_gather_rays) instead of the closed forms (False).
        """
    @monte_carlo_gathers.setter
    def monte_carlo_gathers(self, arg0: bool) -> None:
        ...
    @property
    def obscurance(self) -> bool:
        """
        Multiply the field by the paper's obscurance, an ambient-occlusion look (False).
        """
    @obscurance.setter
    def obscurance(self, arg0: bool) -> None:
        ...
    @property
    def obscurance_distance(self) -> float:
        """
        R_max (m) of the obscurance; 0 = two cells.
        """
    @obscurance_distance.setter
    def obscurance_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def obscurance_rays(self) -> int:
        """
        Directions N_d of the obscurance estimate (32, the paper's).
        """
    @obscurance_rays.setter
    def obscurance_rays(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def obscurance_weight(self) -> float:
        """
        w_oc of the obscurance (1).
        """
    @obscurance_weight.setter
    def obscurance_weight(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def occlusion_test(self) -> bool:
        """
        Skip sample points a surface separates from the shading point (a shadow ray per lookup; not in the paper) (True).
        """
    @occlusion_test.setter
    def occlusion_test(self, arg0: bool) -> None:
        ...
    @property
    def photons(self) -> int:
        """
        Photons emitted per pass (200000).
        """
    @photons.setter
    def photons(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def resolution(self) -> int:
        """
        SH-grid cells along the bounds' longest side, 1..128 (32, the paper's).
        """
    @resolution.setter
    def resolution(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def seed(self) -> int:
        """
        Random seed (0).
        """
    @seed.setter
    def seed(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def side_test(self) -> bool:
        """
        Skip sample points behind the shading point's tangent plane (True).
        """
    @side_test.setter
    def side_test(self, arg0: bool) -> None:
        ...
    @property
    def specular_roughness(self) -> float:
        """
        Lobes up to this roughness make caustic paths (0.1).
        """
    @specular_roughness.setter
    def specular_roughness(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def use_bounds(self) -> bool:
        """
        Use bounds_min/bounds_max instead of the scene's bounds (False).
        """
    @use_bounds.setter
    def use_bounds(self, arg0: bool) -> None:
        ...
    @property
    def use_mips(self) -> bool:
        """
        Read coarser radiance-grid levels for distant hits (True).
        """
    @use_mips.setter
    def use_mips(self, arg0: bool) -> None:
        ...
    @property
    def visibility_test(self) -> bool:
        """
        Skip sample points the distance SH says are hidden (False).
        """
    @visibility_test.setter
    def visibility_test(self, arg0: bool) -> None:
        ...
    @property
    def world_in_field(self) -> bool:
        """
        Gather rays that leave the scene read the world, and renderers skip the world in next-event estimation (False).
        """
    @world_in_field.setter
    def world_in_field(self, arg0: bool) -> None:
        ...
class RouletteSurvival:
    """
    Russian roulette's survival probability for a path of throughput T (largest component).
    
    Members:
    
      SQRT_THROUGHPUT
    
      THROUGHPUT
    """
    SQRT_THROUGHPUT: typing.ClassVar[RouletteSurvival]  # value = <RouletteSurvival.SQRT_THROUGHPUT: 0>
    THROUGHPUT: typing.ClassVar[RouletteSurvival]  # value = <RouletteSurvival.THROUGHPUT: 1>
    __members__: typing.ClassVar[dict[str, RouletteSurvival]]  # value = {'SQRT_THROUGHPUT': <RouletteSurvival.SQRT_THROUGHPUT: 0>, 'THROUGHPUT': <RouletteSurvival.THROUGHPUT: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: RouletteSurvival) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: RouletteSurvival) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class Scene:
    """
    
    Meshes, instances, materials, textures, lights, world and camera, plus the Embree BVH that
    answers ray queries. Build it with add_*, call commit(), then query. Any edit un-commits.
    Editing while another thread commits or queries the scene raises RuntimeError.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self) -> None:
        """
        An empty scene.
        """
    def add_instance(self, mesh_id: typing.SupportsIndex, world_from_object: typing.Any = None, name: str = '') -> int:
        """
        Places mesh `mesh_id` with a (4, 4) row-major matrix (Blender's matrix_world; None = identity); returns the instance id.
        """
    def add_light(self, light: Light) -> int:
        """
        Adds a Light; returns its id.
        """
    def add_material(self, material: Material) -> int:
        """
        Adds a Material; returns its id (the index triangles' material_indices use).
        """
    def add_mesh(self, mesh: typing.Any = None, *, positions: typing.Any = None, triangles: typing.Any = None, normals: typing.Any = None, uvs: typing.Any = None, material_indices: typing.Any = None, name: str = '', tangents: typing.Any = None) -> int:
        """
        Adds a mesh (an shgi.Mesh, or keyword arrays) and returns its id. Degenerate triangles are dropped (see stats()). positions: (N, 3) float, object space (m); triangles: (T, 3) int vertex indices, counter-clockwise = front; normals: (N, 3) float or None; uvs: (N, 2) float (UV map 'UVMap'), a dict {name: (N, 2)} or None; material_indices: (T,) int or None (all 0); tangents: (N, 4) float (object-space MikkTSpace tangent of the normal map's UV map, then the bitangent sign +-1) or None; NaN or zero tangents are dropped with a warning (no normal map there).
        """
    def add_texture(self, texture: Texture) -> int:
        """
        Adds a Texture; returns its id (Material.base_color_texture).
        """
    def bounds(self) -> tuple[tuple, tuple]:
        """
        World-space bounds ((x0, y0, z0), (x1, y1, z1)); ValueError for an empty scene.
        """
    def commit(self, memory_budget_bytes: typing.SupportsIndex = 0, progress: Progress = None, flatten_single_use_meshes: bool = True) -> None:
        """
        Checks cross references and builds the BVH, with the GIL released: a mesh used by one instance goes into the top-level BVH in world space (flatten_single_use_meshes; False instances every mesh, with the same hits), a mesh used by several is instanced. Raises MemoryError when the BVH would exceed memory_budget_bytes (0 = 75% of what the process may still allocate: RLIMIT_AS, cgroup limit, free memory), shgi.Cancelled when progress.cancel() is called.
        """
    def emissive_triangles(self) -> dict:
        """
        Emissive triangles gathered at commit: dict of p0, p1, p2 (K, 3) world space, area (K,) m^2, radiance (K, 3), instance_id and triangle_id (K,).
        """
    def intersect(self, origins: typing.Any, directions: typing.Any, tmin: typing.Any = 0.0, tmax: typing.Any = ..., progress: Progress = None) -> dict:
        """
        Closest hits of a batch of rays: dict of hit (N,) bool, t (N,) float32 (inf on a miss), instance_id and triangle_id (N,) uint32 (0xFFFFFFFF on a miss), barycentrics (N, 2) float32 (b1, b2), normal (N, 3) unit world-space geometric normal (0 on a miss). origins, directions: (N, 3) float (directions need not be unit: t is in units of their length); tmin, tmax: scalars or (N,) arrays (tmax may be inf). The GIL is released; progress (shgi.Progress) reports and cancels (shgi.Cancelled). ValueError names the first invalid ray (NaN, zero direction, tmax < tmin).
        """
    def occluded(self, origins: typing.Any, directions: typing.Any, tmin: typing.Any = 0.0, tmax: typing.Any = ..., progress: Progress = None) -> numpy.typing.NDArray[numpy.bool]:
        """
        (N,) bool: True where something lies between tmin and tmax. origins, directions: (N, 3) float (directions need not be unit: t is in units of their length); tmin, tmax: scalars or (N,) arrays (tmax may be inf). The GIL is released; progress (shgi.Progress) reports and cancels (shgi.Cancelled). ValueError names the first invalid ray (NaN, zero direction, tmax < tmin).
        """
    def set_camera(self, camera: Camera) -> None:
        """
        Sets the Camera.
        """
    def set_instance_transform(self, instance_id: typing.SupportsIndex, world_from_object: typing.Any) -> None:
        """
        Moves an instance; the next commit() rebuilds only the top-level BVH.
        """
    def set_light(self, light_id: typing.SupportsIndex, light: Light) -> None:
        """
        Replaces a Light; the next commit() rebuilds no BVH.
        """
    def set_lights(self, lights: collections.abc.Sequence[Light]) -> None:
        """
        Replaces every Light (ids are the list's indices); the next commit() rebuilds no BVH.
        """
    def set_material(self, material_id: typing.SupportsIndex, material: Material) -> None:
        """
        Replaces a Material (triangles keep their material ids); the next commit() rebuilds no BVH.
        """
    def set_mesh(self, mesh_id: typing.SupportsIndex, mesh: Mesh) -> None:
        """
        Replaces mesh `mesh_id` (an shgi.Mesh, checked and cleaned as add_mesh does) for every instance of it, e.g. with one that has a new lightmap UV map; the next commit() rebuilds its BVH. ValueError naming the id and the mesh count for a bad mesh_id.
        """
    def set_texture(self, texture_id: typing.SupportsIndex, texture: Texture) -> None:
        """
        Replaces a Texture; the next commit() rebuilds no BVH.
        """
    def set_world(self, world: World) -> None:
        """
        Sets the World (uniform background light).
        """
    def stats(self) -> dict:
        """
        Dict of counts: meshes, instances, triangles, instanced_triangles, dropped_degenerate, emissive_triangles, lights, bvh_bytes (peak of the last commit that built a BVH), bvh_builds (Embree builds so far: per-mesh and top-level), flattened_instances (instances whose mesh is in the top-level BVH itself).
        """
    @property
    def camera(self) -> Camera:
        """
        A copy of the Camera (ValueError if none was set).
        """
    @property
    def committed(self) -> bool:
        """
        True after a successful commit.
        """
    @property
    def empty(self) -> bool:
        """
        True when no instance has triangles.
        """
    @property
    def has_camera(self) -> bool:
        """
        True once set_camera ran.
        """
    @property
    def instances(self) -> list[Instance]:
        """
        Copies of the instances.
        """
    @property
    def lights(self) -> list[Light]:
        """
        Copies of the lights.
        """
    @property
    def materials(self) -> list[Material]:
        """
        Copies of the materials.
        """
    @property
    def meshes(self) -> list[Mesh]:
        """
        Copies of the (cleaned) meshes.
        """
    @property
    def textures(self) -> list[Texture]:
        """
        Copies of the textures.
        """
    @property
    def world(self) -> World:
        """
        A copy of the World.
        """
class SensorFit:
    """
    Blender's camera sensor fit.
    
    Members:
    
      AUTO
    
      HORIZONTAL
    
      VERTICAL
    """
    AUTO: typing.ClassVar[SensorFit]  # value = <SensorFit.AUTO: 0>
    HORIZONTAL: typing.ClassVar[SensorFit]  # value = <SensorFit.HORIZONTAL: 1>
    VERTICAL: typing.ClassVar[SensorFit]  # value = <SensorFit.VERTICAL: 2>
    __members__: typing.ClassVar[dict[str, SensorFit]]  # value = {'AUTO': <SensorFit.AUTO: 0>, 'HORIZONTAL': <SensorFit.HORIZONTAL: 1>, 'VERTICAL': <SensorFit.VERTICAL: 2>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: SensorFit) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: SensorFit) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
class TexelMap:
    """
    
    The sample positions of every texel of one object's lightmap (rasterize_texels). Arrays are
    (height, width) with row 0 at v = 0.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @property
    def chart(self) -> numpy.typing.NDArray[numpy.int32]:
        """
        (H, W) int32 UV chart of each texel, -1 where nothing is covered.
        """
    @property
    def chart_count(self) -> int:
        """
        UV charts (islands) of the mesh.
        """
    @property
    def coverage(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (H, W) float32 fraction of each texel the UV layout covers.
        """
    @property
    def height(self) -> int:
        ...
    @property
    def instance_id(self) -> int:
        ...
    @property
    def normals(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (H, W, 3) float32 mean shading normal of each texel (+Z where nothing is covered): a denoiser's normal guide.
        """
    @property
    def positions(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (H, W, 3) float32 mean world position (m) of each texel (0 where nothing is covered).
        """
    @property
    def report(self) -> dict:
        """
        What rasterizing skipped or clipped (dict of counts).
        """
    @property
    def sample_count(self) -> int:
        ...
    @property
    def width(self) -> int:
        ...
class TexelRasterSettings:
    """
    Where lightmap texels lie: resolution, UV map and samples per texel.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        TexelRasterSettings(**fields)
        """
    @property
    def height(self) -> int:
        """
        Texels along v (256).
        """
    @height.setter
    def height(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def samples_per_axis(self) -> int:
        """
        Sample positions per texel side, 1..16 (2: 4 per texel).
        """
    @samples_per_axis.setter
    def samples_per_axis(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def uv_set(self) -> str:
        """
        The lightmap UV map's name ('LightmapUV').
        """
    @uv_set.setter
    def uv_set(self, arg0: str) -> None:
        ...
    @property
    def width(self) -> int:
        """
        Texels along u (256).
        """
    @width.setter
    def width(self, arg1: typing.SupportsIndex) -> None:
        ...
class Texture:
    """
    A linear RGBA image; row 0 is the bottom row (Blender).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, pixels: typing.Any, name: str = '') -> None:
        """
        Builds a texture from an (H, W, 4) or (H, W, 3) float array of linear values, row 0 at the bottom as in Blender's Image.pixels (alpha 1 when absent).
        """
    @property
    def height(self) -> int:
        """
        Height in pixels.
        """
    @property
    def name(self) -> str:
        """
        The image name.
        """
    @name.setter
    def name(self, arg0: str) -> None:
        ...
    @property
    def pixels(self) -> numpy.typing.NDArray[numpy.float32]:
        """
        (H, W, 4) float32 copy of the texels.
        """
    @property
    def width(self) -> int:
        """
        Width in pixels.
        """
class UnoccludeSettings:
    """
    Moving texel samples out of walls (Godot's unocclude).
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        UnoccludeSettings(**fields)
        """
    @property
    def push_distance(self) -> float:
        """
        Texels past the wall, [0, 16] (0.05).
        """
    @push_distance.setter
    def push_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
    @property
    def ray_count(self) -> int:
        """
        Tangent-plane rays per sample (8).
        """
    @ray_count.setter
    def ray_count(self, arg1: typing.SupportsIndex) -> None:
        ...
    @property
    def search_radius(self) -> float:
        """
        Texels searched for walls, (0, 16] (1).
        """
    @search_radius.setter
    def search_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class World:
    """
    Uniform background light: color * strength.
    """
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    def __init__(self, **kwargs) -> None:
        """
        World(**fields), e.g. World(strength=2.0).
        """
    @property
    def color(self) -> tuple:
        """
        Linear RGB background colour.
        """
    @color.setter
    def color(self, arg1: typing.Any) -> None:
        ...
    @property
    def strength(self) -> float:
        """
        >= 0.
        """
    @strength.setter
    def strength(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None:
        ...
class WorldSampling:
    """
    How next-event estimation samples the world.
    
    Members:
    
      COSINE
    
      UNIFORM
    """
    COSINE: typing.ClassVar[WorldSampling]  # value = <WorldSampling.COSINE: 0>
    UNIFORM: typing.ClassVar[WorldSampling]  # value = <WorldSampling.UNIFORM: 1>
    __members__: typing.ClassVar[dict[str, WorldSampling]]  # value = {'COSINE': <WorldSampling.COSINE: 0>, 'UNIFORM': <WorldSampling.UNIFORM: 1>}
    @staticmethod
    def _pybind11_conduit_v1_(*args, **kwargs):
        ...
    @typing.overload
    def __eq__(self, other: WorldSampling) -> bool:
        ...
    @typing.overload
    def __eq__(self, other: typing.Any) -> bool:
        ...
    def __getstate__(self) -> int:
        ...
    def __hash__(self) -> int:
        ...
    def __index__(self) -> int:
        ...
    def __init__(self, value: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __int__(self) -> int:
        ...
    @typing.overload
    def __ne__(self, other: WorldSampling) -> bool:
        ...
    @typing.overload
    def __ne__(self, other: typing.Any) -> bool:
        ...
    def __repr__(self) -> str:
        ...
    def __setstate__(self, state: typing.SupportsInt | typing.SupportsIndex) -> None:
        ...
    def __str__(self) -> str:
        ...
    @property
    def name(self) -> str:
        ...
    @property
    def value(self) -> int:
        ...
def bake_lightmap(scene: Scene, map: TexelMap, settings: LightmapSettings = ..., field: IndirectField = None, tiles: collections.abc.Sequence[typing.SupportsIndex] = [], progress: Progress = None) -> LightmapTexels:
    """
    Bakes `tiles` (all when empty) of the texel map: with the path tracer when `field` is None, else with the field's indirect light.
    """
def dilate_lightmap(texels: LightmapTexels, padding: typing.SupportsIndex = 4, progress: Progress = None) -> numpy.typing.NDArray[numpy.bool]:
    """
    Spreads every layer `padding` texels beyond the charts in place; returns the (H, W) bool mask of texels holding a value.
    """
def filter_lightmap(map: TexelMap, texels: LightmapTexels, settings: LightmapFilterSettings = ..., progress: Progress = None) -> None:
    """
    Filters the baked texels in place.
    """
def lightmap_read_tiles(width: typing.SupportsIndex, height: typing.SupportsIndex, tile_size: typing.SupportsIndex, tiles: collections.abc.Sequence[typing.SupportsIndex], field: IndirectField = None) -> list[int]:
    """
    The tiles whose texels a bake of `tiles` with `field` reads (an interleaved field's filter reaches into neighbouring tiles): a shard unoccludes these. Empty for all.
    """
def lightmap_shard_tiles(width: typing.SupportsIndex, height: typing.SupportsIndex, tile_size: typing.SupportsIndex, shard: typing.SupportsIndex, shards: typing.SupportsIndex) -> list[int]:
    """
    Tiles shard i of N bakes: every tile t with t % N == i.
    """
def lightmap_tile_count(width: typing.SupportsIndex, height: typing.SupportsIndex, tile_size: typing.SupportsIndex) -> int:
    ...
def linear_from_srgb(encoded: typing.Annotated[numpy.typing.ArrayLike, numpy.float32]) -> typing.Any:
    """
    Inverse sRGB transfer function: x / 12.92 up to 0.04045, ((x + 0.055) / 1.055)**2.4 above.
    Input is clamped to [0, 1] (NaN -> 0). Accepts a float or an array (float32 result).
    """
def load_gltf(path: str | bytes | os.PathLike, *, lighting_mode: str = 'SPEC', import_lights: bool = True, import_camera: bool = True, import_textures: bool = True, light_radius: typing.SupportsFloat | typing.SupportsIndex = 0.25, sun_angle: typing.SupportsFloat | typing.SupportsIndex = 0.009180432185530663, progress: Progress = None) -> Scene:
    """
    Loads the default scene of a glTF 2.0 file (.gltf or .glb) into a new, uncommitted Scene, as
    Blender 3.4's glTF importer would import it.
    
    Y-up glTF becomes Z-up ((x, y, z) -> (x, -z, y)); UV v becomes 1 - v; each glTF mesh is
    one mesh (its TRIANGLES primitives merged, a material per triangle, as Blender's material
    slots), instanced once per node that uses it; TEXCOORD_n are UV sets "UVMap", "UVMap.001",
    ...; the base colour texture is decoded to linear RGBA; the first camera node sets the camera.
    lighting_mode: how KHR_lights_punctual intensities become Blender units, as the importer's
        "Lighting Mode": "SPEC" (point/spot W = cd * 4 pi / 683, sun W/m^2 = lux / 683), "COMPAT"
        (W = cd * 4 pi, sun = lux) or "RAW" (values copied).
    import_lights, import_camera, import_textures: skip those parts when False.
    light_radius (m), sun_angle (rad): what glTF's punctual lights lack; the defaults are Blender's
        new-light defaults (0.25 m, 0.526 degrees), which its importer keeps. 0 gives point lights.
    Raises OSError naming the file when it is missing, malformed or uses unsupported required
    extensions; problems that only cost a part (an undecodable image, a non-triangle primitive) are
    logged as warnings.
    """
def load_obj(path: str | bytes | os.PathLike, *, up_axis: str = 'Y', progress: Progress = None) -> Scene:
    """
    Loads a Wavefront OBJ file and the .mtl files it names (looked up beside it) into a new,
    uncommitted Scene, as Blender 3.4's OBJ importer would import it.
    
    One mesh per OBJ object/group, each instanced once with the identity transform; polygons are
    triangulated; vt coordinates become UV set "UVMap". MTL statements map to materials as Blender
    maps them: Kd base colour, Ke emission, Ks specular, Ns roughness = 1 - sqrt(Ns / 1000),
    Ni IOR, Pr/Pm (PBR extension) roughness/metallic; d/Tr are ignored.
    up_axis: "Y" (the importer's default: forward -Z, up Y, converted to Z-up) or "Z" (no change).
    Raises OSError naming the file when it is missing or malformed, or when a face refers to a
    vertex, normal or UV that does not exist; a missing .mtl is logged as a warning.
    progress: a shgi.Progress ("reading", then "importing" shape by shape); its cancel, or Ctrl-C,
        stops the load with shgi.Cancelled (KeyboardInterrupt) between shapes.
    """
def log_level() -> LogLevel:
    """
    The current minimum log level.
    """
def make_native_solver(method: str, scene: Scene, settings: typing.Any = None, progress: Progress = None) -> GiSolver:
    """
    The solver of a native method on a committed scene (settings None: the defaults); use shgi.make_solver, which also knows methods registered from Python.
    """
def max_threads() -> int:
    """
    The number of worker threads SHGI may use.
    """
def memory_limits() -> dict:
    """
    The bytes this process may still allocate, as every large allocation checks them first (docs/robustness-memory.md): {'address_space_left': RLIMIT_AS minus the virtual size, 'cgroup_left': the cgroup memory limit minus its usage, 'available': MemAvailable, 'allowed': the smallest, 'limited_by': which}; None where there is no such limit.
    """
def merge_lightmap(into: LightmapTexels, part: LightmapTexels) -> None:
    """
    Copies the texels `part` baked into `into` (ValueError when shards overlap).
    """
def native_methods() -> list[NativeMethod]:
    """
    The native registry's rows, in menu order (shgi.methods() adds Python ones).
    """
def propagation_steps(settings: PropagationSettings) -> int:
    """
    The steps a PropagationVolume of these settings propagates: settings.steps, or with steps 0 settings.distance over the order's cells per step (LPV 0.915, HOLPV 1.415), rounded. Raises ValueError for invalid settings.
    """
def rasterize_texels(scene: Scene, instance: typing.SupportsIndex, settings: TexelRasterSettings = ..., progress: Progress = None) -> TexelMap:
    """
    Rasterizes instance `instance`'s lightmap UV map; ValueError naming the object when the UV map is missing (listing the ones it has) or the mesh is bad.
    """
def read_exr(path: str | bytes | os.PathLike, max_pixels: typing.SupportsIndex = 268435456) -> dict:
    """
    Reads an OpenEXR file into a dict of layer name -> float32 array (H, W, C), row 0 at the top.
    
    Layers and channels come back in the order write_exr wrote them; for files from other writers
    layers are in the file's (alphabetical) order and channels in Blender's order (R G B A,
    X Y Z W, U V, others by name). Half channels are converted to float32. Channels named without a
    '.' form the layer "". read_exr_info gives the channel names and pixel types.
    max_pixels: refuse images with more than this many pixels (width * height), so that a hostile
        file cannot exhaust memory; raise it only for trusted files.
    Raises OSError naming the file when it is missing, corrupt, too large or unsupported.
    """
def read_exr_info(path: str | bytes | os.PathLike) -> dict:
    """
    Reads only the header of an OpenEXR file: {"width", "height", "compression",
    "channels": [(full name, "half" | "float"), ...]} with channels in read_exr's order.
    Raises OSError naming the file when it is missing, corrupt or unsupported.
    """
def render_path_traced(scene: Scene, settings: PathTracerSettings = ..., progress: Progress = None) -> dict:
    """
    Renders settings.samples samples per pixel of the scene's camera; returns {pass name: float32 array (H, W, C)}.
    """
def render_preview(scene: Scene, field: IndirectField, settings: PreviewSettings = ..., camera: Camera = None, progress: Progress = None) -> tuple[dict, dict]:
    """
    Renders settings.samples samples per pixel with indirect light from `field` (None: direct only); returns (passes dict, timings dict in seconds).
    """
def reserved_method_numbers() -> list[tuple[str, int]]:
    """
    (identifier, number) of methods still to come: their numbers stay reserved.
    """
def set_log_level(level: LogLevel) -> None:
    """
    Drops messages below `level` before they reach the sink.
    """
def set_log_sink(sink: collections.abc.Callable | None) -> None:
    """
    Routes SHGI's log messages to sink(level: LogLevel, message: str); None restores stderr. The shgi package installs a sink that forwards to logging.getLogger('shgi').
    """
def set_max_threads(threads: typing.SupportsIndex) -> None:
    """
    Limits SHGI's worker threads (0 = all cores). Results do not depend on it.
    """
def srgb_from_linear(linear: typing.Annotated[numpy.typing.ArrayLike, numpy.float32]) -> typing.Any:
    """
    sRGB transfer function (IEC 61966-2-1): 12.92 x up to 0.0031308, 1.055 x**(1/2.4) - 0.055
    above. Input is clamped to [0, 1] (NaN -> 0). Accepts a float or an array (float32 result).
    """
def trace_photon_batch(scene: Scene, settings: PhotonLatticeSettings, pass_index: typing.SupportsIndex, begin: typing.SupportsIndex, end: typing.SupportsIndex, progress: Progress = None) -> PhotonBatch:
    """
    Photons [begin, end) of pass `pass_index` of a PhotonLattice with `settings` on the committed scene, as a PhotonBatch (GIL released; shgi.Cancelled on cancel; ValueError unless begin < end <= settings.photons). Each photon's path depends only on the seed, the pass, its index and settings.photons, so any split merges into the single solve.
    """
def unocclude(scene: Scene, map: TexelMap, settings: UnoccludeSettings = ..., progress: Progress = None, tiles: collections.abc.Sequence[typing.SupportsIndex] = [], tile_size: typing.SupportsIndex = 16) -> dict:
    """
    Moves the ray origins of samples inside other geometry out of it; returns counts. `tiles` (lightmap tiles of `tile_size` texels, as bake_lightmap numbers them; empty: all): only their texels' samples, each moved exactly as by a whole unocclude (what a shard bakes).
    """
def version() -> str:
    """
    SHGI's version string.
    """
def write_exr(path: str | bytes | os.PathLike, layers: dict, pixel_type: str | None = None, channel_names: dict = {}, compression: str = 'zip') -> None:
    """
    Writes a multilayer OpenEXR file, atomically (temporary file in the same folder, then rename).
    
    layers: dict of layer name -> float16/32/64 array (H, W) or (H, W, C), all the same H x W, row 0
        at the top. Channels are named "<layer>.<suffix>" (Blender's style: "Combined.R",
        "Depth.Z"); suffixes default to R G B A (4), R G B (3), X Y (2), Z (1). An empty layer name
        writes bare suffixes ("R", "G", "B").
    pixel_type: "float" (exact), "half", or None: half for float16 arrays, float otherwise.
    channel_names: dict of layer name -> suffixes, a str with one per character ("XYZ") or a list
        of str (["c0", "c1", ...]); needed for layers with more than 4 channels.
    compression: lossless codec "zip" (default), "piz", "zips", "rle" or "none".
    Raises ValueError for bad arrays or names (naming the argument), OSError when the file cannot
    be written.
    """
def write_png(path: str | bytes | os.PathLike, pixels: typing.Any, exposure: typing.SupportsFloat | typing.SupportsIndex = 0.0, premultiplied: bool = True) -> None:
    """
    Writes linear float pixels as an 8-bit sRGB PNG, atomically.
    
    pixels: float array (H, W, 3) RGB or (H, W, 4) RGBA, linear Rec.709, row 0 at the top.
    exposure: stops; colour is multiplied by 2**exposure before encoding.
    premultiplied: RGBA colour is premultiplied by alpha (as SHGI and Cycles render it) and is
        divided by alpha before encoding, since PNG stores straight alpha.
    Colour is clamped to [0, 1] (NaN -> 0) and encoded with the exact sRGB curve; alpha is stored
    linearly. Raises ValueError for bad arguments, OSError when the file cannot be written.
    """
MAX_COORDINATE: float = 999999995904.0
MAX_LIGHTMAP_RESOLUTION: int = 16384
