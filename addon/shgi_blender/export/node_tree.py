"""Walking Blender shader node trees: the active output and what feeds an input socket."""

REROUTE_NODE = "NodeReroute"
# Output node targets that Cycles (and so SHGI) renders.
RENDERED_OUTPUT_TARGETS = ("ALL", "CYCLES")


def active_output(node_tree, output_idname):
    """The output node of type `output_idname` Cycles would use, or None.

    Blender marks one output node per type as active; its target must include Cycles.
    """
    outputs = [node for node in node_tree.nodes if node.bl_idname == output_idname
               and getattr(node, "target", "ALL") in RENDERED_OUTPUT_TARGETS]
    active = [node for node in outputs if node.is_active_output]
    return (active or outputs or [None])[0]


def linked_output(socket):
    """The output socket that drives `socket` (through reroutes, skipping muted links), or None."""
    while socket is not None and socket.is_linked:
        links = [link for link in socket.links if not getattr(link, "is_muted", False)]
        if not links:
            return None
        node = links[0].from_node
        if node.bl_idname != REROUTE_NODE:
            return links[0].from_socket
        socket = node.inputs[0] if node.inputs else None
    return None


def linked_node(socket):
    """The node whose output drives `socket` (through reroutes, skipping muted links), or None."""
    output = linked_output(socket)
    return None if output is None else output.node


def input_values(node):
    """{input name: unlinked value} of a node's inputs; colours and vectors as tuples."""
    values = {}
    for socket in node.inputs:
        if not hasattr(socket, "default_value"):
            continue
        value = socket.default_value
        values[socket.name] = tuple(value) if hasattr(value, "__len__") else value
    return values
