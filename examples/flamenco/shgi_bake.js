// SPDX-License-Identifier: GPL-3.0-or-later
//
// SHGI lightmap bake: a Flamenco 3 job type (job compiler script) that splits one lightmap
// bake over the farm. Install: copy this file into the `scripts` folder next to the
// flamenco-manager executable and restart the Manager (examples/flamenco/README.md).
//
// The job becomes three stages of tasks:
//   prepare      one task: checks the add-on on a worker, selects the objects, gives them the
//                lightmap UV map (Lightmap Pack, saved into the job's .blend so every shard
//                sees the same UVs) when `create_uv` is on, creates the output folder;
//   bake-shard-i shard_count tasks, each depending on prepare only (they run in parallel):
//                shard i of N bakes every lightmap tile t with t % N == i (tiles counted over
//                all objects in name order) and writes raw shard files into <output>/shards;
//   merge        one task depending on every shard: merges the shard files and writes
//                <object>.exr / <object>.png, byte-identical to a bake on one machine.
// With shard_count 1 there is a single `bake` task (after prepare) and no merge.
//
// Runners:
//   "blender" (default): `blender -b <blendfile> --python-exit-code 1 --python-expr ...` runs
//       the add-on's operators bpy.ops.shgi.bake_lightmaps(shard_index=i, shard_count=N, ...)
//       and bpy.ops.shgi.merge_lightmap_shards(shard_count=N, ...). The SHGI add-on and its
//       native module must be installed for the Blender the workers run ({blender}).
//   "python": no Blender: `python3 -m shgi bake <scene_file> --out DIR --shard i/N` and
//       `--merge N` on a glTF/OBJ scene (its lightmap UV map: LightmapUV, else TEXCOORD_1).
//       The `shgi` package must be importable by the workers' `python_exe`.
// Every setting a task needs is passed explicitly, so all shards and the merge bake alike.

const JOB_TYPE = {
    label: "SHGI Lightmap Bake",
    description: "Bake SHGI lightmaps of the selected objects in shards, then merge them",
    settings: [
        // What to bake.
        { key: "objects", type: "string", visible: "submission",
          eval: "', '.join(sorted(o.name for o in C.selected_objects if o.type == 'MESH'))",
          evalInfo: { showLinkButton: true, description: "The selected mesh objects" },
          description: "Comma-separated names of the mesh objects to bake (the selection " +
                       "saved in the file when empty)" },
        { key: "uv_map", type: "string", default: "LightmapUV", visible: "submission",
          eval: "C.scene.shgi.bake.uv_map",
          evalInfo: { showLinkButton: true, description: "The Bake panel's UV Map" },
          description: "The lightmap UV map (one per object, inside the unit square, " +
                       "without overlaps)" },
        { key: "create_uv", type: "bool", default: false, visible: "submission",
          description: "Give objects without the UV map one (Lightmap Pack) in the prepare " +
                       "task, saved into the job's copy of the .blend file" },
        // How to bake: the names of the add-on's bake properties.
        { key: "resolution", type: "int32", default: 0, propargs: { min: 0, max: 16384 },
          visible: "submission", eval: "C.scene.shgi.bake.resolution",
          evalInfo: { showLinkButton: true, description: "The Bake panel's Resolution" },
          description: "Texels per side of every lightmap; 0 sizes each from the texel density" },
        { key: "texel_density", type: "float", default: 32.0, visible: "submission",
          eval: "C.scene.shgi.bake.texel_density",
          evalInfo: { showLinkButton: true, description: "The Bake panel's Texel Density" },
          description: "Texels per metre of surface, used when the resolution is 0" },
        { key: "samples", type: "int32", default: 256, propargs: { min: 1, max: 1048576 },
          visible: "submission", eval: "C.scene.shgi.bake.samples",
          evalInfo: { showLinkButton: true, description: "The Bake panel's Samples" },
          description: "Samples per texel" },
        { key: "content", type: "string", default: "DIRECT_INDIRECT", visible: "submission",
          choices: ["DIRECT_INDIRECT", "DIRECT", "INDIRECT", "FULL"],
          description: "What a texel holds, in the units of Cycles' Diffuse bake" },
        { key: "source", type: "string", default: "PATH_TRACE", visible: "submission",
          choices: ["PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID", "RADIANCE_FIELD", "PROPAGATION"],
          description: "Where the indirect light comes from (PATH_TRACE: ground truth)" },
        { key: "directional", type: "bool", default: false, visible: "submission",
          description: "Also write the SH layers per texel (SH.c0..c3; SH.c0..c8 at sh_order 2)" },
        { key: "sh_order", type: "int32", default: 1, propargs: { min: 1, max: 2 },
          visible: "submission", description: "With directional: 1 (L1) or 2 (L2) SH" },
        { key: "filter", type: "bool", default: false, visible: "submission",
          description: "Edge-aware denoising filter (run once, by the merge)" },
        { key: "padding", type: "int32", default: 4, propargs: { min: 0, max: 64 },
          visible: "submission", description: "Texels of dilation beyond the UV charts" },
        { key: "output_folder", type: "string", subtype: "dir_path", required: true,
          visible: "submission", eval: "bpy.path.abspath(C.scene.shgi.bake.output_folder)",
          evalInfo: { showLinkButton: true, description: "The Bake panel's Output Folder" },
          description: "Where <object>.exr/.png are written (shard files go to its shards/ " +
                       "folder); must be on storage every worker reaches" },
        // How to split it.
        { key: "shard_count", type: "int32", default: 4, propargs: { min: 1, max: 4096 },
          visible: "submission",
          description: "Shards (parallel tasks); each bakes every N-th tile of all lightmaps" },
        // Where it runs.
        { key: "runner", type: "string", default: "blender", choices: ["blender", "python"],
          visible: "submission",
          description: "blender: the add-on's operators on the .blend file; python: " +
                       "`python3 -m shgi bake` on scene_file (glTF/OBJ)" },
        { key: "scene_file", type: "string", subtype: "file_path", visible: "submission",
          description: "runner python: the .gltf/.glb/.obj scene to bake" },
        { key: "python_exe", type: "string", default: "python3", visible: "submission",
          description: "runner python: the Python that can import shgi on the workers" },
        // Filled in by the Flamenco add-on when submitting from Blender.
        { key: "blendfile", type: "string", visible: "web",
          description: "Path of the .blend file to bake (runner blender)" },
    ],
};

function compileJob(job) {
    const settings = job.settings;
    checkSettings(settings);
    const commands = settings.runner === "python" ? pythonCommands : blenderCommands;
    const shards = settings.shard_count;

    const prepare = commands.prepare(settings);
    if (prepare) job.addTask(prepare);

    if (shards === 1) {
        const bake = commands.bake(settings, null);
        if (prepare) bake.addDependency(prepare);
        job.addTask(bake);
        return;
    }
    // Shards depend only on prepare, so the Manager hands them to idle workers in parallel.
    const shardTasks = [];
    for (let index = 0; index < shards; index++) {
        const task = commands.bake(settings, index);
        if (prepare) task.addDependency(prepare);
        job.addTask(task);
        shardTasks.push(task);
    }
    // The merge needs every shard's files: it waits for all of them.
    const merge = commands.merge(settings);
    for (const task of shardTasks) merge.addDependency(task);
    job.addTask(merge);
}

function checkSettings(settings) {
    if (!(Number.isInteger(settings.shard_count) && settings.shard_count >= 1)) {
        throw `shard_count must be a whole number >= 1, not ${settings.shard_count}`;
    }
    if (!settings.output_folder) {
        throw "output_folder is empty: choose a folder that every worker reaches";
    }
    if (settings.resolution <= 0 && !(settings.texel_density > 0)) {
        throw "resolution and texel_density are both 0: set one of them";
    }
    if (settings.runner === "python") {
        if (!settings.scene_file) throw "runner python needs scene_file (a .gltf, .glb or .obj)";
    } else if (settings.runner === "blender") {
        if (!settings.blendfile) throw "runner blender needs blendfile (submit from Blender)";
    } else {
        throw `runner must be "blender" or "python", not "${settings.runner}"`;
    }
}

// The `objects` setting as a list of names (empty: the file's own selection).
function objectNames(settings) {
    if (!settings.objects) return [];
    return settings.objects.split(",").map((name) => name.trim()).filter((name) => name !== "");
}

// --- runner "blender": the add-on's operators in background Blender ---------------------------

// A Python literal of a JS value (JSON strings are valid Python string literals).
function py(value) {
    if (typeof value === "boolean") return value ? "True" : "False";
    if (typeof value === "number") return String(value);
    return JSON.stringify(String(value));
}

// The operator properties every bake and merge task passes: the same for all of them. The
// operators take the rest (tile size, seed, light paths) from the .blend file's scene, which
// every task opens. create_uv=False: prepare made the UV maps; a shard must not lay out its own.
// farm='LOCAL': each task bakes its own shard on its worker (a file saved with Bake > Farm set
// to Flamenco or Dask would otherwise refuse, or send the shard on to a Dask cluster).
function operatorArguments(settings) {
    const names = ["uv_map", "resolution", "texel_density", "samples", "content", "source",
                   "directional", "sh_order", "filter", "padding", "output_folder"];
    const values = names.map((name) => `${name}=${py(settings[name])}`);
    return values.concat(["create_uv=False", "farm='LOCAL'"]).join(", ");
}

// Python that selects exactly the job's objects (the operators bake the selected meshes) and
// finds the add-on's package (shgi_blender, or bl_ext.<repository>.shgi_blender on 4.2+).
function pythonPrologue(settings) {
    return [
        "import bpy, importlib, os, types",
        "addon = next((name for name in bpy.context.preferences.addons.keys()",
        "              if name.rsplit('.', 1)[-1] == 'shgi_blender'), None)",
        "if addon is None:",
        "    raise RuntimeError('SHGI farm bake: the SHGI add-on (shgi_blender) is not enabled "
            + "in the Blender this worker runs; enable it in its Preferences')",
        `names = ${JSON.stringify(objectNames(settings))}`,
        "if names:",
        "    layer = bpy.context.view_layer",
        "    missing = [name for name in names if name not in layer.objects]",
        "    if missing:",
        "        raise RuntimeError(f'SHGI farm bake: no object {missing} in the view layer of '",
        "                           f'{bpy.data.filepath}')",
        "    for obj in layer.objects:",
        "        obj.select_set(obj.name in names)",
    ];
}

// The operator's result must be FINISHED; a bake that reports an error raises by itself.
function pythonOperatorCall(call, what) {
    return [
        `result = ${call}`,
        "if result != {'FINISHED'}:",
        `    raise RuntimeError(f'SHGI farm bake: ${what} ended {result}')`,
    ];
}

function blenderTask(settings, name, lines) {
    const task = author.Task(name, "blender");
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: settings.blendfile,
        // --python-exit-code: an exception in the script fails the task instead of Blender
        // exiting 0 with a traceback in the log.
        args: ["--python-exit-code", "1", "--python-expr", lines.join("\n")],
    }));
    return task;
}

const blenderCommands = {
    prepare(settings) {
        // The add-on's own checks and Lightmap Pack (operators/bake_lightmaps.py), so the
        // farm lays out UV maps exactly as the Bake panel's Create UV Map does.
        const lines = pythonPrologue(settings).concat([
            "ops = importlib.import_module(addon + '.operators.bake_lightmaps')",
            "objects = ops.selected_meshes(bpy.context)",
            `values = types.SimpleNamespace(uv_map=${py(settings.uv_map)}, ` +
                `create_uv=${py(settings.create_uv)}, uv_layout='LIGHTMAP_PACK')`,
            "ops.prepare_uv_maps(bpy.context, objects, values, " +
                "lambda level, text: print(*level, text), [])",
            `os.makedirs(os.path.join(ops.output_dir(${py(settings.output_folder)}), 'shards'), ` +
                "exist_ok=True)",
            "print(f'SHGI farm bake: {len(objects)} objects ready:', " +
                "', '.join(obj.name for obj in objects))",
        ]);
        // Every shard opens the saved file, so they all bake the same UV layout.
        if (settings.create_uv) lines.push("bpy.ops.wm.save_mainfile()");
        return blenderTask(settings, "prepare", lines);
    },

    bake(settings, index) {
        const shard = index === null ? "" : `, shard_index=${index}, ` +
            `shard_count=${settings.shard_count}`;
        const what = index === null ? "the bake" : `shard ${index} of ${settings.shard_count}`;
        const call = `bpy.ops.shgi.bake_lightmaps(${operatorArguments(settings)}${shard})`;
        const lines = pythonPrologue(settings).concat(pythonOperatorCall(call, what));
        return blenderTask(settings, index === null ? "bake" : `bake-shard-${index}`, lines);
    },

    merge(settings) {
        const call = `bpy.ops.shgi.merge_lightmap_shards(${operatorArguments(settings)}, ` +
            `shard_count=${settings.shard_count})`;
        const lines = pythonPrologue(settings).concat(pythonOperatorCall(call, "the merge"));
        return blenderTask(settings, "merge", lines);
    },
};

// --- runner "python": `python3 -m shgi bake` on a glTF/OBJ scene ------------------------------

// The CLI options every bake and merge task passes (the same for all of them).
function cliArguments(settings) {
    const args = ["-m", "shgi", "bake", settings.scene_file, "--out", settings.output_folder,
                  "--samples", String(settings.samples), "--content", settings.content,
                  "--method", settings.source, "--padding", String(settings.padding),
                  "--quiet"];
    // An empty uv_map lets the CLI choose (LightmapUV, else a glTF's TEXCOORD_1 'UVMap.001').
    if (settings.uv_map) args.push("--uv-set", settings.uv_map);
    if (settings.resolution > 0) args.push("--resolution", String(settings.resolution));
    else args.push("--density", String(settings.texel_density));
    if (settings.objects) args.push("--objects", objectNames(settings).join(","));
    if (settings.directional) args.push("--directional");
    if (settings.directional && settings.sh_order === 2) args.push("--sh-order", "2");
    if (settings.filter) args.push("--filter");
    return args;
}

function pythonTask(settings, name, extra) {
    const task = author.Task(name, "misc");
    // `exec` runs the executable directly (no shell); its exit status decides the task.
    task.addCommand(author.Command("exec", {
        exe: settings.python_exe,
        args: cliArguments(settings).concat(extra),
    }));
    return task;
}

const pythonCommands = {
    prepare(_settings) {
        return null;  // the CLI creates its folders; it checks the scene in every task
    },
    bake(settings, index) {
        if (index === null) return pythonTask(settings, "bake", []);
        return pythonTask(settings, `bake-shard-${index}`,
                          ["--shard", `${index}/${settings.shard_count}`]);
    },
    merge(settings) {
        return pythonTask(settings, "merge", ["--merge", String(settings.shard_count)]);
    },
};
