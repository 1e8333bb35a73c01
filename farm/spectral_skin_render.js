// SPDX-License-Identifier: GPL-3.0-or-later
//
// Flamenco 3 job type: render a .blend whose skin materials Spectral Skin set up, in chunks of frames; optionally
// re-apply the skins first, headless, with overrides (one task every render task depends on).
//
// Install: copy this file into the `scripts/` folder next to the Flamenco Manager executable and restart the Manager
// (docs/farm.md). Workers need only Blender to render (Apply writes plain Blender data: textures, F-curves, drivers);
// the re-apply task needs the Spectral Skin extension installed and enabled in the worker's Blender.
//
// Written against Flamenco 3's job-type API (flamenco.blender.org/usage/job-types; the built-in
// simple_blender_render.js of Flamenco 3.x): JOB_TYPE {label, settings}, compileJob(job), author.Task,
// author.Command("blender-render", {exe, exeArgs, argsBefore, blendfile, args}), task.addDependency, frameChunker,
// path. Tested without a farm by tests/python/test_farm_jobs.py (Node, against the stand-in tests/farm/flamenco_api.js).

const JOB_TYPE = {
    label: "Spectral Skin Render",
    description: "Render frames of a .blend set up by Spectral Skin; optionally re-apply its skins on a worker first",
    settings: [
        // Set by the artist at submission.
        { key: "frames", type: "string", required: true,
          eval: "f'{C.scene.frame_start}-{C.scene.frame_end}'",
          evalInfo: { showLinkButton: true, description: "Scene frame range" },
          description: "Frames to render, e.g. '1-30' or '3, 5-10, 47'" },
        { key: "chunk_size", type: "int32", default: 1, required: true,
          description: "Frames rendered by one task (one Blender start per task)" },
        { key: "reapply", type: "bool", default: false,
          description: "Re-apply the skins on a worker before rendering (the worker needs the Spectral Skin extension)" },
        { key: "reapply_materials", type: "string", default: "",
          description: "Materials to re-apply, comma-separated (re-apply only)" },
        { key: "reapply_overrides", type: "string", default: "",
          description: "Batch-apply overrides, e.g. '--preset asian --hemoglobin 0.02' (re-apply only; flags of " +
                       "the extension's batch.py apply)" },
        { key: "render_output_root", type: "string", subtype: "dir_path", required: true, visible: "submission",
          description: "Folder the frames go into (a subfolder per job)" },
        // Computed at submission.
        { key: "render_output_path", type: "string", subtype: "file_path", editable: false,
          eval: "str(Path(abspath(settings.render_output_root), jobname, '######'))",
          description: "Final file path of the frames (#: frame number)" },
        // Filled in by Flamenco's Blender add-on at submission (the path on the shared storage), as for the built-in
        // job types.
        { key: "blendfile", type: "string", required: true, visible: "web",
          description: "The .blend to render" },
        { key: "format", type: "string", required: true, eval: "C.scene.render.image_settings.file_format",
          visible: "web" },
    ],
};

// The Blender expression that runs the extension's batch apply on the arguments after "--" and ends Blender with its
// exit status (batch.py: 0 done, 2 an error that names the input; nothing is saved on an error).
const APPLY_EXPR = "import importlib, os, sys; " +
    "name = next(n for n in sys.modules if n.startswith('bl_ext.') and n.endswith('.spectral_skin')); " +
    "status = importlib.import_module(name + '.batch').main(sys.argv[sys.argv.index('--') + 1:]); " +
    "sys.stdout.flush(); sys.stderr.flush(); os._exit(status)";

function splitWords(text) {
    return (text || "").split(/\s+/).filter((word) => word.length > 0);
}

// The re-applied copy of the .blend, next to it (the textures are packed into it).
function appliedBlendfile(blendfile) {
    return blendfile.replace(/\.blend$/, "") + ".spectral-skin.blend";
}

function authorApplyTask(settings) {
    const materials = (settings.reapply_materials || "").split(",").map((m) => m.trim()).filter((m) => m);
    if (materials.length === 0) {
        throw "re-apply needs at least one material name (reapply_materials)";
    }
    const args = ["apply", settings.blendfile, appliedBlendfile(settings.blendfile), "--pack"];
    for (const material of materials) {
        args.push("--material", material);
    }
    const task = author.Task("spectral-skin-apply", "blender");
    task.addCommand(author.Command("blender-render", {
        exe: "{blender}",
        exeArgs: "{blenderArgs}",
        argsBefore: [],
        blendfile: settings.blendfile,
        args: ["--python-expr", APPLY_EXPR, "--"].concat(args, splitWords(settings.reapply_overrides)),
    }));
    return task;
}

function authorRenderTasks(settings, renderOutput, blendfile) {
    const tasks = [];
    for (const chunk of frameChunker(settings.frames, settings.chunk_size)) {
        const task = author.Task(`render-${chunk}`, "blender");
        task.addCommand(author.Command("blender-render", {
            exe: "{blender}",
            exeArgs: "{blenderArgs}",
            argsBefore: [],
            blendfile: blendfile,
            args: [
                "--render-output", renderOutput,
                "--render-format", settings.format,
                // Flamenco's chunks are "1-4" or "9,10"; Blender's frame ranges are "1..4".
                "--render-frame", chunk.replaceAll("-", ".."),
            ],
        }));
        tasks.push(task);
    }
    return tasks;
}

function compileJob(job) {
    const settings = job.settings;
    if (!settings.render_output_path) {
        throw "no render_output_path setting";
    }
    if (!(settings.chunk_size >= 1)) {
        throw `chunk_size must be 1 or more, not ${settings.chunk_size}`;
    }
    const renderOutput = path.join(path.dirname(settings.render_output_path), path.basename(settings.render_output_path));
    const apply = settings.reapply ? authorApplyTask(settings) : null;
    const blendfile = apply ? appliedBlendfile(settings.blendfile) : settings.blendfile;
    if (apply) {
        job.addTask(apply);
    }
    for (const task of authorRenderTasks(settings, renderOutput, blendfile)) {
        if (apply) {
            task.addDependency(apply);
        }
        job.addTask(task);
    }
}
