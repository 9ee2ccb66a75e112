// Compiles a job of shgi_bake.js outside Flamenco and prints its tasks, their dependencies and
// the command lines a worker would run; with --run it also runs them here, one at a time in
// dependency order (a farm of one machine), so a job script can be tried before the Manager
// sees it.
//
//   node preview_job.js '{"runner": "python", "scene_file": "room.gltf", ...}' [--run]
//   node preview_job.js @shgi_flamenco_job.json [--run]
//
// The JSON holds job settings, or a whole job with them under "settings" (the add-on's Write
// Flamenco Job); the rest take the defaults of JOB_TYPE. Only the parts of
// Flamenco's job-compiler API that shgi_bake.js uses are provided (author.Task,
// author.Command, job.addTask, task.addDependency, print). Variables as Flamenco's default
// configuration expands them: {blender} -> "blender", {blenderArgs} -> "-b -y".
"use strict";

const childProcess = require("child_process");
const fs = require("fs");
const nodePath = require("path");
const vm = require("vm");

const VARIABLES = { "{blender}": "blender", "{blenderArgs}": "-b -y" };

function expand(text) {
    return Object.keys(VARIABLES).reduce((out, key) => out.split(key).join(VARIABLES[key]), text);
}

// The worker's command line for one command (blender-render or exec).
function commandLine(command) {
    const p = command.parameters;
    if (command.name === "blender-render") {
        const exeArgs = expand(p.exeArgs).split(" ").filter((arg) => arg !== "");
        return [expand(p.exe), ...exeArgs, ...p.argsBefore, p.blendfile, ...p.args];
    }
    if (command.name === "exec") return [p.exe, ...p.args];
    throw new Error(`preview_job.js does not know the command "${command.name}"`);
}

function compile(scriptPath, overrides) {
    const tasks = [];
    const author = {
        Task: (name, type) => ({
            name, type, commands: [], dependencies: [],
            addCommand(command) { this.commands.push(command); },
            addDependency(task) { this.dependencies.push(task); },
        }),
        Command: (name, parameters) => ({ name, parameters }),
    };
    const context = vm.createContext({ author, print: console.log });
    vm.runInContext(fs.readFileSync(scriptPath, "utf8") + "\nthis.JOB_TYPE = JOB_TYPE;",
                    context, { filename: scriptPath });
    const settings = {};
    for (const setting of context.JOB_TYPE.settings) {
        if (setting.default !== undefined) settings[setting.key] = setting.default;
    }
    Object.assign(settings, overrides);
    context.compileJob({ settings, addTask: (task) => tasks.push(task) });
    return tasks;
}

// Tasks ordered so that each comes after everything it depends on (throws on a cycle).
function dependencyOrder(tasks) {
    const done = new Set();
    const order = [];
    while (order.length < tasks.length) {
        const ready = tasks.filter((t) => !done.has(t) && t.dependencies.every((d) => done.has(d)));
        if (ready.length === 0) throw new Error("the job's task dependencies form a cycle");
        for (const task of ready) {
            done.add(task);
            order.push(task);
        }
    }
    return order;
}

function main() {
    const args = process.argv.slice(2);
    const run = args.includes("--run");
    const json = args.find((arg) => arg !== "--run");
    // Job settings, or a whole job as a Manager takes it ({"name", "type", "settings", ...}:
    // what the add-on's Write Flamenco Job writes), inline or as @file.
    const text = json && json.startsWith("@") ? fs.readFileSync(json.slice(1), "utf8") : json;
    const parsed = text ? JSON.parse(text) : {};
    const tasks = compile(nodePath.join(__dirname, "shgi_bake.js"), parsed.settings || parsed);
    for (const task of dependencyOrder(tasks)) {
        const after = task.dependencies.map((d) => d.name).join(", ") || "nothing";
        console.log(`task ${task.name} (${task.type}), after ${after}`);
        for (const command of task.commands) {
            const line = commandLine(command);
            console.log("  " + line.map((arg) => JSON.stringify(arg)).join(" "));
            if (!run) continue;
            const result = childProcess.spawnSync(line[0], line.slice(1), { stdio: "inherit" });
            if (result.status !== 0) {
                console.error(`task ${task.name} failed (exit ${result.status}); stopping`);
                process.exit(1);
            }
        }
    }
}

main();
