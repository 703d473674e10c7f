// Synth page: drop an exemplar, synthesise more of it (a synth job), see the result beside it -
// as a 2x2 tiling when tileable - and download it. Option changes re-run the job on the same
// upload ("from_job"); at most one job runs for the page, later changes collapse into the latest.
"use strict";
nav("Synth");
const $ = id => document.getElementById(id);
let source = null;       // the job whose uploaded image is the exemplar
let current = null;      // the job running now
let events = null;
let pending = null;      // options waiting for the running job to end
let results = 0;

function options() {
  const size = parseInt($("size").value);
  return { size, tileable: $("tileable").checked, seed: parseInt($("seed").value) || 0,
           randomness_scale: parseFloat($("randomness").value), downscale: $("downscale").checked };
}

// Swaps the exemplar in once the new image has loaded (no blank box in between).
function showExemplar(url) {
  const img = new Image();
  img.onload = () => { $("drop").innerHTML = ""; $("drop").appendChild(img); };
  img.src = url;
}

// Uploads a new exemplar: the first job of that upload.
async function upload(file) {
  showError($("error"));
  showExemplar(URL.createObjectURL(file));
  const form = new FormData();
  form.append("exemplar", file);
  form.append("options", new Blob([JSON.stringify(options())], { type: "application/json" }));
  source = null;
  pending = null;
  await submit(() => apiJson("/api/jobs/synth", { method: "POST", body: form }), true);
}

// Re-runs on the current exemplar with the current options (one job at a time).
function rerun() {
  if (!source) return;
  pending = Object.assign(options(), { from_job: source });
  if (!current) pump();
}

async function pump() {
  while (pending && !current) {
    const body = pending;
    pending = null;
    await submit(() => apiJson("/api/jobs/synth", { method: "POST", headers: { "Content-Type": "application/json" },
                                                    body: JSON.stringify(body) }), false);
  }
}

async function submit(post, isUpload) {
  if (events) events.close();
  $("stage").textContent = isUpload ? "uploading…" : "queued";
  $("meter").style.width = "0%";
  let job;
  try {
    job = await post();
  } catch (e) {
    $("stage").textContent = "";
    showError($("error"), e);
    return;
  }
  if (isUpload) source = job.id;
  current = job;
  document.body.dataset.job = job.id;
  $("stop").disabled = false;
  $("go").disabled = false;
  await new Promise(resolve => {
    events = new EventSource(withToken("/api/jobs/" + job.id + "/events"));
    events.addEventListener("progress", ev => {
      const d = JSON.parse(ev.data), p = d.progress || {};
      $("meter").style.width = Math.round(100 * (p.fraction || 0)) + "%";
      $("stage").textContent = d.state === "queued" ? "queued" : (p.stage || "starting") +
        (p.elapsed ? " · " + p.elapsed.toFixed(1) + " s" : "");
    });
    events.addEventListener("done", ev => {
      events.close();
      show(JSON.parse(ev.data));
      resolve();
    });
    events.onerror = () => {
      if (events.readyState === EventSource.CLOSED) { $("stage").textContent += " · connection lost"; resolve(); }
    };
  });
  current = null;
  $("stop").disabled = true;
  if (pending) pump();
}

function show(status) {
  if (!status.result) {
    $("stage").textContent = status.state + (status.error ? ": " + status.error : "");
    if (status.error) showError($("error"), status.error);
    return;
  }
  showError($("error"));
  const r = status.result, files = "/api/jobs/" + status.id + "/files/";
  const url = withToken(files + r.files.synth);
  const img = $("result-img");
  img.onload = () => {
    results++;
    const view = $("result");
    // At the exemplar's pixel scale when it fits (the exemplar is shown 1:1 too); a tileable
    // result 2x2, so a seam at the wrap would show as a cross in the middle.
    const room = r.tileable ? view.clientWidth / 2 : view.clientWidth;
    const scale = Math.min(1, room / Math.max(r.size[0], r.size[1]));
    view.style.backgroundImage = "url('" + url + "')";
    view.style.backgroundSize = Math.round(r.size[0] * scale) + "px " + Math.round(r.size[1] * scale) + "px";
    view.style.backgroundRepeat = r.tileable ? "repeat" : "no-repeat";
    view.dataset.tiled = r.tileable ? "1" : "0";
    view.dataset.results = results;
    $("tiling-label").textContent = (r.tileable ? "· tiled 2x2" : "") + (scale < 1 ? " · shown at " + Math.round(100 * scale) + "%" : " · 1:1");
    document.body.dataset.done = String(results);
  };
  img.src = url;
  showExemplar(withToken(files + r.files.exemplar));
  $("meter").style.width = "100%";
  $("stage").textContent = "done · " + r.size[0] + "x" + r.size[1] + " in " + r.timings.total.toFixed(2) + " s";
  const ex = r.exemplar;
  $("exemplar-info").textContent = "exemplar " + ex.width + "x" + ex.height + (ex.downscaled ? " (scaled from " + ex.uploaded.join("x") + ")" : "") +
    (ex.tiles ? " · tiles" : " · bounded") + " · " + r.levels + " levels";
  $("result-info").textContent = r.size[0] + "x" + r.size[1] + " · seed " + r.seed + " · randomness " + r.randomness.join(", ") +
    " · analysis " + (r.analysis_cached ? "cached" : r.timings.analysis.toFixed(2) + " s") + " · synthesis " + r.timings.synthesis.toFixed(2) + " s";
  $("result-info").dataset.seed = r.seed;
  $("dl-png").href = withToken(files + r.files.synth + "?download=1");
  $("dl-exemplar").href = withToken(files + r.files.exemplar + "?download=1");
  $("dl-result").href = withToken(files + r.files.result);
  $("downloads").hidden = false;
  $("command").textContent = r.command;
}

async function listUploads() {
  try {
    const jobs = (await apiJson("/api/jobs")).jobs.filter(j => (j.kind === "synth" || j.kind === "match") && j.params && j.params.input);
    const box = $("reuse");
    while (box.options.length > 1) box.remove(1);
    for (const j of jobs)
      box.add(new Option(j.kind + " · " + j.id.slice(0, 8) + " · " + new Date(j.created * 1000).toLocaleTimeString(), j.id));
  } catch (e) { showError($("error"), e); }
}

(async () => {
  try {
    const h = await apiJson("/api/health");
    for (const o of [...$("size").options]) if (parseInt(o.value) > h.limits.max_synth_size) o.remove();
  } catch (e) {}
  listUploads();
  const q = new URLSearchParams(location.search);
  if (q.get("job")) useJob(q.get("job"));
})();

// The exemplar of an earlier job (a match photo or a synth exemplar): no second upload.
async function useJob(id) {
  try {
    const j = await apiJson("/api/jobs/" + id);
    source = id;
    showExemplar(withToken("/api/jobs/" + id + "/files/" + j.params.input));
    rerun();
  } catch (e) { showError($("error"), e); }
}
$("reuse").onchange = () => $("reuse").value && useJob($("reuse").value);
$("randomness").oninput = () => { $("randomness-value").textContent = parseFloat($("randomness").value).toFixed(2); };
$("randomness").onchange = rerun;
for (const id of ["size", "tileable", "seed", "downscale"]) $(id).onchange = rerun;
$("new-seed").onclick = () => { $("seed").value = Math.floor(Math.random() * 4294967296); rerun(); };
$("go").onclick = rerun;
$("stop").onclick = () => current && api("/api/jobs/" + current.id + "/cancel", { method: "POST" }).catch(e => showError($("error"), e));
$("file").onchange = () => $("file").files[0] && upload($("file").files[0]);
const drop = $("drop");
drop.ondragover = e => { e.preventDefault(); drop.classList.add("over"); };
drop.ondragleave = () => drop.classList.remove("over");
drop.ondrop = e => { e.preventDefault(); drop.classList.remove("over"); if (e.dataTransfer.files[0]) upload(e.dataTransfer.files[0]); };
