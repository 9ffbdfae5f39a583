// SPDX-License-Identifier: MIT
// A Flamenco 3 custom job type that renders a shot with nerfpt: one task per chunk of frames, each running
//   nerfpt render SCENE -o OUT --frames FIRST-LAST [EXTRA]
// Install: copy this file into the Manager's `scripts/` folder and restart it; Workers need `nerfpt` (or the
// path given as `nerfpt`). Frames already written are skipped by nerfpt, so a requeued task renders only what
// is missing. tests/cli/farm_test.sh runs the commands this file compiles.

const JOB_TYPE = {
    label: "nerfpt render",
    settings: [
        { key: "nerfpt", type: "string", default: "nerfpt", description: "The nerfpt binary on the Workers" },
        { key: "scene", type: "string", subtype: "file_path", required: true, description: "Scene (.gltf, .glb, .json)" },
        { key: "output", type: "string", subtype: "file_path", required: true,
          description: "Frames, #### replaced by the frame number (e.g. renders/shot.####.exr)" },
        { key: "frame_first", type: "int32", required: true, default: 1 },
        { key: "frame_last", type: "int32", required: true, default: 48 },
        { key: "chunk_size", type: "int32", default: 8, description: "Frames per task" },
        { key: "extra_args", type: "string", default: "", description: "More options, e.g. --spp 256 --res 1920x1080" },
    ],
};

// The tasks' frame ranges: contiguous chunks of chunk_size frames, FIRST-LAST as `nerfpt render --frames` takes.
function nerfptChunks(first, last, size) {
    const chunks = [];
    for (let start = first; start <= last; start += size) chunks.push(`${start}-${Math.min(start + size - 1, last)}`);
    return chunks;
}

function nerfptArgs(settings, frames) {
    const args = ["render", settings.scene, "-o", settings.output, "--frames", frames];
    const extra = (settings.extra_args || "").trim();
    return extra ? args.concat(extra.split(/\s+/)) : args;
}

function compileJob(job) {
    const settings = job.settings;
    if (settings.frame_last < settings.frame_first) throw "frame_last must not be before frame_first";
    for (const frames of nerfptChunks(settings.frame_first, settings.frame_last, Math.max(1, settings.chunk_size))) {
        const task = author.Task(`nerfpt ${frames}`, "misc");
        task.addCommand(author.Command("exec", { exe: settings.nerfpt, args: nerfptArgs(settings, frames) }));
        job.addTask(task);
    }
}
