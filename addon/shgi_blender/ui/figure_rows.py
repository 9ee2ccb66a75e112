"""Figures the panels show as (label, value) rows, without bpy.

A row is drawn as a split, label on the left and its value on the right, so each value sits
beside its own label (a two-column grid_flow fills column by column: its labels and values
would not line up pairwise).
"""

from ..engine import solution_cache

# The last render's timings (FinalRender.record["timings"]), in the order of a render.
RENDER_TIMING_LABELS = {"export": "Export", "commit": "BVH", "solve": "Solve",
                        "render": "Render", "denoise": "Denoise", "total": "Total"}
# Share of a row's width taken by the label.
LABEL_FACTOR = 0.5


def render_timing_rows(timings):
    """[(label, "1.23 s")] of a render's timings: the known stages in order, then the others."""
    order = [key for key in RENDER_TIMING_LABELS if key in timings]
    order += [key for key in timings if key not in RENDER_TIMING_LABELS]
    return [(RENDER_TIMING_LABELS.get(key, key.capitalize()), f"{timings[key]:.2f} s")
            for key in order]


def solution_rows(solution):
    """[(label, value)] of a frozen solution: stage timings, the solver's figures, memory."""
    rows = [(label, f"{1000.0 * solution.timings[key]:.1f} ms")
            for key, label in solution_cache.TIMING_LABELS.items() if key in solution.timings]
    rows += [(label, text) for label, text in solution.solver.figures()]
    rows.append(("Memory", f"{solution.memory_bytes / solution_cache.BYTES_PER_MIB:.2f} MiB"))
    return rows


def draw_rows(layout, rows):
    """Draws each (label, value) as one row of `layout`: the label beside its value."""
    column = layout.column(align=True)
    for label, value in rows:
        split = column.split(factor=LABEL_FACTOR, align=True)
        split.label(text=label)
        split.label(text=value)
