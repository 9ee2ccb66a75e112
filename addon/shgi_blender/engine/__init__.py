"""The SHGI render engine: F12 renders with Cycles' passes, frozen solutions, and the live
viewport (Rendered shading).

* bpy-free: passes.py (pass table, pixel layout), native_task.py (a cancellable worker
  thread), render_job.py (the worker-thread render; make_renderer), field_solvers.py (the
  PhotonLattice and ProbeGrid solvers driven alike: build, update passes, field),
  solution_cache.py (solves, and frozen solutions per scene), scene_checks.py (warnings about
  scenes that render black), lightmap_bake.py (lightmap bakes on a worker thread); for the
  viewport sync_plan.py (what an edit invalidates), viewport_camera.py (the view as a
  shgi.Camera), viewport_worker.py (the worker thread: build, commit, solve or refine in the
  background, progressive frames), field_spheres.py and lattice_samples.py (the overlays'
  spheres: lattice cells, probes);
* bpy: render_engine.py (the RenderEngine class, registration), final_render.py (F12),
  viewport.py (view_update / view_draw sessions), viewport_sync.py (depsgraph updates ->
  scene snapshots), frame_display.py (gpu drawing of frames).
"""


def register():
    from . import render_engine
    render_engine.register()


def unregister():
    from . import render_engine
    render_engine.unregister()
