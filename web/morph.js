// Morph page: keys from the library or from match results, a morph job, animation + filmstrip.
"use strict";
nav("Morph");
const $ = id => document.getElementById(id);
const keys = [];  // {spec} or {job, spec}
let job = null, source = null;

async function thumb(spec) {
  const res = await api("/api/render", { method: "POST", headers: { "Content-Type": "application/json" },
                                         body: JSON.stringify({ spec, size: 64 }) });
  return URL.createObjectURL(await res.blob());
}

async function drawKeys() {
  $("keys").innerHTML = keys.length ? "" : '<div class="dim">add two or more keys</div>';
  for (let i = 0; i < keys.length; ++i) {
    const row = document.createElement("div");
    row.className = "key";
    const img = document.createElement("img");
    thumb(keys[i].spec).then(u => img.src = u).catch(() => {});
    const label = document.createElement("span");
    label.textContent = keys[i].spec.shader + (keys[i].job ? " (match " + keys[i].job.slice(0, 8) + ")" : "");
    const rm = document.createElement("button");
    rm.textContent = "×";
    rm.onclick = () => { keys.splice(i, 1); drawKeys(); };
    row.append(img, label, rm);
    $("keys").appendChild(row);
  }
}

async function addJob(id) {
  const r = await apiJson("/api/jobs/" + id + "/result");
  keys.push({ job: id, spec: r.spec });
  drawKeys();
}

(async () => {
  try {
    for (const s of await shaders()) $("add-shader").add(new Option(s.name, s.name));
    const jobs = (await apiJson("/api/jobs")).jobs.filter(j => j.kind === "match" && j.has_result);
    for (const j of jobs) $("add-job").add(new Option((j.progress.best_shader || "match") + " · " + j.id.slice(0, 8), j.id));
    const q = new URLSearchParams(location.search);
    if (q.get("key")) keys.push({ spec: JSON.parse(q.get("key")) });
    if (q.get("job")) await addJob(q.get("job"));
    drawKeys();
  } catch (e) { showError($("error"), e); }
})();

$("add").onclick = () => { keys.push({ spec: { shader: $("add-shader").value, params: {}, seed: 0 } }); drawKeys(); };
$("add-match").onclick = () => $("add-job").value && addJob($("add-job").value).catch(e => showError($("error"), e));

$("go").onclick = async () => {
  showError($("error"));
  if (source) source.close();
  const body = { keys: keys.map(k => k.job ? { job: k.job } : k.spec),
                 frames: parseInt($("frames").value), size: parseInt($("size").value), fps: parseInt($("fps").value) };
  try {
    job = await apiJson("/api/jobs/morph", { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  } catch (e) { return showError($("error"), e); }
  $("stop").disabled = false;
  $("go").disabled = true;
  source = new EventSource(withToken("/api/jobs/" + job.id + "/events"));
  source.addEventListener("progress", ev => {
    const d = JSON.parse(ev.data), p = d.progress || {};
    $("meter").style.width = Math.round(100 * (p.fraction || 0)) + "%";
    $("stage").textContent = d.state + (p.stage ? " · " + p.stage : "") + (p.elapsed ? " · " + p.elapsed.toFixed(1) + " s" : "");
  });
  source.addEventListener("done", ev => { source.close(); show(JSON.parse(ev.data)); });
};

$("stop").onclick = () => job && api("/api/jobs/" + job.id + "/cancel", { method: "POST" }).catch(e => showError($("error"), e));

function show(status) {
  $("stop").disabled = true;
  $("go").disabled = false;
  if (!status.result) { $("stage").textContent = status.state + (status.error ? ": " + status.error : ""); return; }
  const r = status.result, files = "/api/jobs/" + status.id + "/files/";
  $("stage").textContent = status.state + " · " + r.files.frames.length + " frames · " + (r.shaders || []).join(" → ");
  $("meter").style.width = "100%";
  $("out").hidden = false;
  if (r.files.gif) $("anim").src = withToken(files + r.files.gif);
  if (r.files.filmstrip) { $("filmstrip").src = withToken(files + r.files.filmstrip); $("strip-panel").hidden = false; }
  const dl = $("downloads");
  dl.innerHTML = "";
  const link = (name, href) => { const a = document.createElement("a"); a.textContent = name; a.href = withToken(href + "?download=1"); dl.appendChild(a); };
  if (r.files.gif) link("GIF", files + r.files.gif);
  link("Manifest JSON", files + r.files.manifest);
  r.files.frames.forEach((f, i) => link("frame " + (i + 1), files + f));
}
