// k8s_check.mjs — the Kubernetes side of the farm tests (docs/design.md §7).
//   node k8s_check.mjs SOURCE_DIR WORK_DIR BIN_DIR COMPARE
// 1. Every document of docker/k8s/*.yaml validates against the Kubernetes API schema
//    (kubernetes-models), and wrong types for the Job fields we use are refused; and no
//    field is unknown to the schema (as `kubectl --validate=strict`: a misspelt or misplaced
//    field, which the schema itself lets through, fails).
// 2. The render Job is Indexed with backoffLimitPerIndex, and --shard-count = completions.
// 3. As the Job controller would: the pod's init containers, then its container, run once
//    per index, concurrently, with JOB_COMPLETION_INDEX set and $(VAR) expanded, the /farm
//    volume mapped to WORK_DIR (empty but for scene.json, as the README's operator leaves
//    it); then the merge Job's command; the result is compared with a single render
//    (COMPARE = farm_compare).
import { readFileSync, readdirSync } from "node:fs";
import { spawn, spawnSync } from "node:child_process";
import path from "node:path";
import { parseAllDocuments } from "yaml";
import { Job } from "kubernetes-models/batch/v1/Job";
import { PersistentVolumeClaim } from "kubernetes-models/v1/PersistentVolumeClaim";

const [sourceDir, workDir, binDir, compare] = process.argv.slice(2);
const kinds = { "batch/v1 Job": Job, "v1 PersistentVolumeClaim": PersistentVolumeClaim };
const fail = (msg) => { console.error(`k8s_check: FAIL: ${msg}`); process.exit(1); };

// ---- 1. schema ----
const docs = [];
const k8sDir = path.join(sourceDir, "docker", "k8s");
for (const file of readdirSync(k8sDir).filter((f) => f.endsWith(".yaml")).sort()) {
  for (const d of parseAllDocuments(readFileSync(path.join(k8sDir, file), "utf8"))) {
    if (d.errors.length) fail(`${file}: ${d.errors[0].message}`);
    const obj = d.toJSON();
    const Model = kinds[`${obj.apiVersion} ${obj.kind}`];
    if (!Model) fail(`${file}: no schema check for ${obj.apiVersion} ${obj.kind}`);
    try { new Model(obj).validate(); } catch (e) { fail(`${file}: ${obj.kind} ${obj.metadata?.name}: ${e.message}`); }
    console.log(`k8s_check: ${file}: ${obj.kind} ${obj.metadata.name} is valid`);
    docs.push(obj);
  }
}
// The schema declares the fields we rely on: wrong types for them are refused (the schema
// allows unknown fields, so a type error is what shows a field is known).
for (const [field, value] of [["completions", "four"], ["backoffLimitPerIndex", "three"], ["completionMode", 1]]) {
  const bad = structuredClone(docs.find((d) => d.kind === "Job" && d.spec.completionMode === "Indexed"));
  bad.spec[field] = value;
  let refused = false;
  try { new Job(bad).validate(); } catch { refused = true; }
  if (!refused) fail(`the schema check accepted spec.${field} = ${JSON.stringify(value)}`);
}

// The schema allows fields it does not know, so a field is known where a value of a wrong
// type for it is refused: each field (object key, at any depth) is given values of every JSON
// type in turn; one that is accepted with each of them is unknown to the schema. The keys of
// the string maps (labels, annotations, ...) are the user's own: not fields, not probed.
const probes = [true, 0.5, "x", [], {}];
const stringMaps = new Set(["labels", "annotations", "nodeSelector", "matchLabels"]);
function unknownFields(Model, obj) {
  const unknown = [];
  const walk = (node, at) => {
    if (Array.isArray(node)) return node.forEach((v, i) => walk(v, [...at, i]));
    if (node === null || typeof node !== "object" || stringMaps.has(at[at.length - 1])) return;
    for (const key of Object.keys(node)) {
      const where = [...at, key];
      const refused = probes.some((probe) => {
        const copy = structuredClone(obj);
        let parent = copy;
        for (const step of at) parent = parent[step];
        parent[key] = probe;
        try { new Model(copy).validate(); return false; } catch (e) {
          const field = "/" + where.join("/");
          return (e.errors ?? []).some((x) => x.instancePath === field || x.instancePath.startsWith(field + "/"));
        }
      });
      if (!refused) unknown.push(where.join("."));
      else walk(node[key], where);
    }
  };
  walk(obj, []);
  return unknown;
}
for (const obj of docs) {
  const unknown = unknownFields(kinds[`${obj.apiVersion} ${obj.kind}`], obj);
  if (unknown.length) fail(`${obj.kind} ${obj.metadata.name}: fields unknown to the Kubernetes API schema: ${unknown.join(", ")}`);
}
// ... and the check finds a misspelt and a misplaced field.
{
  const bad = structuredClone(docs.find((d) => d.kind === "Job" && d.spec.completionMode === "Indexed"));
  bad.spec.backoffLimitPerIndx = 3;
  bad.spec.template.spec.completions = 4; // a Job's field, in the pod template
  const found = unknownFields(Job, bad).join(" ");
  if (found !== "spec.template.spec.completions spec.backoffLimitPerIndx")
    fail(`the unknown-field check found '${found}' in a Job with two planted unknown fields`);
}
console.log("k8s_check: no field unknown to the schema (a planted misspelt and misplaced field are found)");

// ---- 2. the render Job's shape ----
const render = docs.find((d) => d.kind === "Job" && d.spec.completionMode === "Indexed");
const merge = docs.find((d) => d.kind === "Job" && d !== render);
if (!render || !merge) fail("expected an Indexed render Job and a merge Job");
if (!(render.spec.backoffLimitPerIndex >= 1)) fail("the render Job has no backoffLimitPerIndex");
const completions = render.spec.completions;
const rc = render.spec.template.spec.containers[0];
const countArg = rc.args[rc.args.indexOf("--shard-count") + 1];
if (String(completions) !== countArg) fail(`--shard-count ${countArg} differs from completions ${completions}`);
const mountOf = (job) => job.spec.template.spec.containers[0].volumeMounts[0].mountPath;
if (mountOf(render) !== mountOf(merge)) fail("the two Jobs mount the shared volume at different paths");
const mount = mountOf(render);

// ---- 3. run the containers' commands as the controller would ----
// The image's ENTRYPOINT is ["tessera"] (docker/Dockerfile): a container with only args
// runs `tessera ARGS`. Kubernetes expands $(NAME) from the container's environment.
const entrypoint = ["tessera"];
const toHost = (s) => s.split(mount).join(workDir);
const expand = (s, env) => s.replace(/\$\(([A-Za-z_][A-Za-z0-9_]*)\)/g, (m, n) => (n in env ? env[n] : m));
function argv(container, env) {
  const cmd = container.command ?? entrypoint;
  const args = container.args ?? [];
  return [...cmd, ...args].map((s) => toHost(expand(s, env)));
}
const baseEnv = { ...process.env, PATH: `${binDir}:${process.env.PATH}` };
function run(words, env, label) {
  return new Promise((resolve) => {
    const p = spawn(words[0], words.slice(1), { env: { ...baseEnv, ...env }, stdio: ["ignore", "inherit", "pipe"] });
    let err = "";
    p.stderr.on("data", (d) => (err += d));
    p.on("close", (code) => resolve({ code, err, label }));
  });
}
const t0 = Date.now();
// One pod: its init containers in order, each to success, then its container.
async function pod(spec, env, label) {
  for (const ic of spec.initContainers ?? []) {
    const r = await run(argv(ic, env), env, `${label} init container ${ic.name}`);
    if (r.code !== 0) return r;
  }
  return run(argv(spec.containers[0], env), env, label);
}
const pods = [];
for (let i = 0; i < completions; i++) {
  const env = { JOB_COMPLETION_INDEX: String(i) };
  pods.push(pod(render.spec.template.spec, env, `index ${i}`));
}
for (const r of await Promise.all(pods)) {
  if (r.code !== 0) fail(`render ${r.label} exited ${r.code}:\n${r.err}`);
  console.log(`k8s_check: render ${r.label}: ${r.err.split("\n").find((l) => l.includes("JOB_COMPLETION_INDEX"))}`);
}
const m = await pod(merge.spec.template.spec, {}, "merge");
if (m.code !== 0) fail(`merge exited ${m.code}:\n${m.err}`);
console.log(`k8s_check: ${m.err.trim().split("\n")[0]}`);
console.log(`k8s_check: ${completions} indexes + merge in ${((Date.now() - t0) / 1000).toFixed(1)} s`);
const ref = path.join(workDir, "reference.exr");
const single = spawnSync("tessera", ["render", path.join(workDir, "scene.json"), "--shard", "0/1", "-o", ref, "--quiet"],
  { env: baseEnv, stdio: "inherit" });
if (single.status !== 0) fail("the single reference render failed");
const cmp = spawnSync(compare, [path.join(workDir, "out", "image.exr"), ref], { stdio: "inherit" });
if (cmp.status !== 0) fail("the merged image differs from the single render");
console.log("k8s_check: passed");
