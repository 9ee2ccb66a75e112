"""The project's example scenes (examples/scenes.py) as tests outside Blender use them."""


def committed(builder):
    """The shgi.Scene of an examples/scenes.py builder, committed and ready to render."""
    builder.scene.commit()
    return builder.scene
