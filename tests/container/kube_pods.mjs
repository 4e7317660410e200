// kube_pods.mjs — the Pods the Kubernetes Job controller would make of docker/k8s, for
// `podman kube play` (tests/container/run.sh). podman 4.3 plays Pods and
// PersistentVolumeClaims but not Jobs, so, as the controller does:
//   - the claim of render-job.yaml, renamed CLAIM (the test's own volume);
//   - one Pod per completion index i of the Indexed Job (completions of them), its pod
//     template unchanged but for: the name PREFIX-<job>-<i>, the annotation
//     batch.kubernetes.io/job-completion-index, JOB_COMPLETION_INDEX=i in each (init)
//     container's environment, $(VAR) references in command and args expanded from that environment
//     (Kubernetes does it; podman 4.3 does not), the image IMAGE and the claim CLAIM;
//   - the merge Job's Pod, the same way.
// Each Pod validates against the Kubernetes API schema (kubernetes-models v1 Pod).
//   node kube_pods.mjs SOURCE_DIR OUT_DIR IMAGE CLAIM PREFIX
// Writes OUT_DIR/claim.yaml, render-pods.yaml (every index, one document each) and
// merge-pod.yaml; prints "render POD..." and "merge POD", then the (main) containers to wait for,
// "render-containers C..." and "merge-containers C..." (podman names a played container
// <pod>-<container>).
import { readFileSync, writeFileSync } from "node:fs";
import path from "node:path";
import { parseAllDocuments, stringify } from "yaml";
import { Pod } from "kubernetes-models/v1/Pod";

const [sourceDir, outDir, image, claim, prefix] = process.argv.slice(2);
const fail = (msg) => { console.error(`kube_pods: ${msg}`); process.exit(1); };
if (!prefix) fail("usage: node kube_pods.mjs SOURCE_DIR OUT_DIR IMAGE CLAIM PREFIX");

const load = (file) => parseAllDocuments(readFileSync(path.join(sourceDir, "docker", "k8s", file), "utf8")).map((d) => {
  if (d.errors.length) fail(`${file}: ${d.errors[0].message}`);
  return d.toJSON();
});
const renderDocs = load("render-job.yaml");
const mergeDocs = load("merge-job.yaml");
const pvc = renderDocs.find((d) => d.kind === "PersistentVolumeClaim");
const render = renderDocs.find((d) => d.kind === "Job" && d.spec.completionMode === "Indexed");
const merge = mergeDocs.find((d) => d.kind === "Job");
if (!pvc || !render || !merge) fail("expected a claim and an Indexed Job in render-job.yaml, a Job in merge-job.yaml");

const expand = (s, env) => s.replace(/\$\(([A-Za-z_][A-Za-z0-9_]*)\)/g, (m, n) => (n in env ? env[n] : m));

function podOf(job, name, index) {
  const spec = structuredClone(job.spec.template.spec);
  const annotations = { ...(job.spec.template.metadata?.annotations ?? {}) };
  for (const c of [...(spec.initContainers ?? []), ...spec.containers]) {
    c.image = image;
    if (index !== undefined) c.env = [...(c.env ?? []), { name: "JOB_COMPLETION_INDEX", value: String(index) }];
    const env = Object.fromEntries((c.env ?? []).filter((e) => "value" in e).map((e) => [e.name, e.value]));
    if (c.command) c.command = c.command.map((s) => expand(s, env));
    if (c.args) c.args = c.args.map((s) => expand(s, env));
  }
  for (const v of spec.volumes ?? []) if (v.persistentVolumeClaim?.claimName === pvc.metadata.name) v.persistentVolumeClaim.claimName = claim;
  if (index !== undefined) annotations["batch.kubernetes.io/job-completion-index"] = String(index);
  const pod = {
    apiVersion: "v1",
    kind: "Pod",
    metadata: { name, labels: { ...(job.spec.template.metadata?.labels ?? {}), "job-name": job.metadata.name }, annotations },
    spec,
  };
  try { new Pod(pod).validate(); } catch (e) { fail(`Pod ${name}: ${e.message}`); }
  return pod;
}

const claimDoc = structuredClone(pvc);
claimDoc.metadata.name = claim;
writeFileSync(path.join(outDir, "claim.yaml"), stringify(claimDoc));
const pods = [];
for (let i = 0; i < render.spec.completions; i++) pods.push(podOf(render, `${prefix}-${render.metadata.name}-${i}`, i));
writeFileSync(path.join(outDir, "render-pods.yaml"), pods.map((p) => stringify(p)).join("---\n"));
const mergePod = podOf(merge, `${prefix}-${merge.metadata.name}`);
writeFileSync(path.join(outDir, "merge-pod.yaml"), stringify(mergePod));
const names = (p) => p.spec.containers.map((c) => `${p.metadata.name}-${c.name}`);
console.log(`render ${pods.map((p) => p.metadata.name).join(" ")}`);
console.log(`merge ${mergePod.metadata.name}`);
console.log(`render-containers ${pods.flatMap(names).join(" ")}`);
console.log(`merge-containers ${names(mergePod).join(" ")}`);
