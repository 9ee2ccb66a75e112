"""The SHGI render engine: F12 renders with Cycles' passes, frozen lattice solutions.

* bpy-free: passes.py (pass table, pixel layout), render_job.py (the worker-thread render),
  solution_cache.py (frozen PhotonLattice solutions per scene), scene_checks.py (warnings
  about scenes that render black);
* bpy: render_engine.py (the RenderEngine class, registration), final_render.py (F12).
"""


def register():
    from . import render_engine
    render_engine.register()


def unregister():
    from . import render_engine
    render_engine.unregister()
