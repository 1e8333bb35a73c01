// A stand-in for the job-compiler API of Flamenco 3 (the globals a job type's script sees), written from Flamenco's
// documentation (flamenco.blender.org/usage/job-types) and source, Flamenco 3.x (projects.blender.org/studio/flamenco,
// mirrored as github.com/blender/flamenco): internal/manager/job_compilers/ (author.go: author.Task(name, type), author.Command(type, parameters[, frameCount]),
// task.addCommand, task.addDependency, job.addTask; js_globals.go: frameChunker (jsFrameChunker, frameRangeExplode,
// frameRangeMerge), path (Go's path/filepath with forward slashes), print, formatTimestampLocal) and the built-in
// scripts/simple_blender_render.js. It records what a compiler authors so that a test can check the task graph.
//
// Usage: node tests/farm/flamenco_api.js JOB_TYPE.js JOB.json   -> prints {"job_type": ..., "tasks": [...]} as JSON.
"use strict";

const fs = require("fs");
const nodePath = require("path");
const vm = require("vm");

// frameRangeExplode: "1-10,20..25,40" -> sorted unique frame numbers ("A-B" and Blender's "A..B" both accepted).
function frameRangeExplode(text) {
    const frames = new Set();
    for (let part of text.split(",")) {
        part = part.trim();
        if (part === "") {
            continue;
        }
        const range = part.match(/^(-?\d+)\s*(?:-|\.\.)\s*(-?\d+)$/);
        if (range) {
            const [first, last] = [Number(range[1]), Number(range[2])];
            if (last < first) {
                throw new Error(`invalid range "${text}": ${part}`);
            }
            for (let frame = first; frame <= last; frame++) {
                frames.add(frame);
            }
        } else if (/^-?\d+$/.test(part)) {
            frames.add(Number(part));
        } else {
            throw new Error(`invalid range "${text}": ${part}`);
        }
    }
    return [...frames].sort((a, b) => a - b);
}

// frameRangeMerge: consecutive frames as "A-B"; a run of one or two frames as single numbers ("9,10").
function frameRangeMerge(frames) {
    const ranges = [];
    const append = (from, to) => {
        if (from === to) {
            ranges.push(String(from));
        } else if (from + 1 === to) {
            ranges.push(String(from), String(to));
        } else {
            ranges.push(`${from}-${to}`);
        }
    };
    let start = frames[0];
    let prev = frames[0];
    for (const frame of frames.slice(1)) {
        if (frame > prev + 1) {
            append(start, prev);
            start = frame;
        }
        prev = frame;
    }
    append(start, prev);
    return ranges.join(",");
}

function frameChunker(frameRange, chunkSize) {
    if (frameRange.trim() === "") {
        throw new Error(`invalid range "${frameRange}": empty range`);
    }
    if (!(chunkSize >= 1)) {
        throw new Error(`invalid chunk size, must be positive number: ${chunkSize}`);
    }
    const frames = frameRangeExplode(frameRange);
    const chunks = [];
    for (let i = 0; i < frames.length; i += chunkSize) {
        chunks.push(frameRangeMerge(frames.slice(i, i + chunkSize)));
    }
    return chunks;
}

class AuthoredTask {
    constructor(name, type) {
        this.name = name;
        this.type = type;
        this.commands = [];
        this.dependencies = [];
    }

    addCommand(command) {
        this.commands.push(command);
    }

    addDependency(task) {
        if (!(task instanceof AuthoredTask)) {
            throw new Error("addDependency takes a task made by author.Task");
        }
        this.dependencies.push(task);
    }
}

const author = {
    Task: (name, type) => new AuthoredTask(name, type),
    Command: (type, parameters, frameCount) => ({ type, parameters, ...(frameCount === undefined ? {} : { frameCount }) }),
};

// Flamenco's path: forward slashes whatever the Manager's platform.
const path = {
    join: (...parts) => nodePath.posix.join(...parts),
    basename: (p) => nodePath.posix.basename(p),
    dirname: (p) => nodePath.posix.dirname(p),
    stem: (p) => nodePath.posix.basename(p, nodePath.posix.extname(p)),
};

function compile(scriptPath, job) {
    const tasks = [];
    const context = {
        author, path, frameChunker,
        print: (...args) => process.stderr.write(args.map(String).join(" ") + "\n"),
        formatTimestampLocal: (date) => new Date(date).toISOString().slice(0, 19).replace(/[-:T]/g, ""),
    };
    vm.createContext(context);
    vm.runInContext(fs.readFileSync(scriptPath, "utf8") + "\n;globalThis.__jobType = JOB_TYPE;", context,
                    { filename: scriptPath });
    context.__job = { ...job, addTask: (task) => tasks.push(task) };
    vm.runInContext("compileJob(__job);", context);
    const known = new Set(tasks);
    return {
        job_type: JSON.parse(JSON.stringify(context.__jobType)),
        tasks: tasks.map((task) => {
            for (const dep of task.dependencies) {
                if (!known.has(dep)) {
                    throw new Error(`task ${task.name} depends on ${dep.name}, which the job does not have`);
                }
            }
            return { name: task.name, type: task.type, commands: task.commands,
                     dependencies: task.dependencies.map((dep) => dep.name) };
        }),
    };
}

if (require.main === module) {
    const [scriptPath, jobPath] = process.argv.slice(2);
    try {
        const result = compile(scriptPath, JSON.parse(fs.readFileSync(jobPath, "utf8")));
        process.stdout.write(JSON.stringify(result, null, 1) + "\n");
    } catch (error) {
        process.stderr.write(`compile error: ${error}\n`);
        process.exit(2);
    }
}

module.exports = { compile, frameChunker };
