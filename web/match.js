// Match page: drop a photo, watch the search (SSE), stop it, tweak the result with sliders.
"use strict";
nav("Match");
const $ = id => document.getElementById(id);
let job = null, source = null, spec = null, live = null;

function setSimilarity(s, verdict) {
  $("similarity").textContent = s > 0 ? s.toFixed(3) : "–";
  $("meter").style.width = Math.round(100 * Math.max(0, Math.min(1, s))) + "%";
  const v = $("verdict");
  v.textContent = verdict || "";
  v.className = "verdict " + (verdict || "");
}

// Why the verdict says what it says (search/match.h, docs/search.md "Verdict"), in the words of the
// command line's summary.
function verdictReason(r) {
  const pct = p => Math.round(100 * p) + "%";
  if (r.pixel_exact)
    return "good: the pattern is reproduced pixel for pixel (RGB RMS difference " + r.image_rmse.toFixed(4) + ")";
  if (r.verdict === "good")
    return "good: " + (r.pattern ? "a clean pattern matched with similarity " + r.similarity.toFixed(2)
                                 : "similar, and " + r.spec.shader + " is " + pct(r.selection_probability) + " likely");
  if (r.verdict === "approximate" && r.similarity < r.thresholds.approximate && r.pattern_similarity != null)
    return "approximate: the same kind of pattern, " + r.pattern_similarity.toFixed(2) +
           " without the spectrum, whose peaks sit elsewhere";
  if (r.verdict === "approximate")
    return "approximate: " + (r.similarity < r.thresholds.good ? "not as similar as another crop of one texture would be"
                                                               : "similar, but the material is not certain enough") +
           " (" + r.spec.shader + " at " + pct(r.selection_probability) + " by the selection, which calls a photo good only at " +
           pct(r.thresholds.good_probability) + "); compare the pictures, or try another shader with --shaders";
  return "no-match: no shader of the library reproduces this photo; try Synth to make more of it from the photo itself";
}

async function start(file) {
  showError($("error"));
  if (source) source.close();
  $("tweak").hidden = true;
  $("drop").innerHTML = "";
  const img = document.createElement("img");
  img.src = URL.createObjectURL(file);
  $("drop").appendChild(img);
  $("preview").removeAttribute("src");
  setSimilarity(0);
  $("verdict-why").textContent = "";
  $("stage").textContent = "uploading…";
  const form = new FormData();
  form.append("photo", file);
  const options = {};
  if ($("budget").value) options.budget = $("budget").value;
  form.append("options", new Blob([JSON.stringify(options)], { type: "application/json" }));
  try {
    job = await apiJson("/api/jobs/match", { method: "POST", body: form });
  } catch (e) {
    $("stage").textContent = "";
    return showError($("error"), e);
  }
  document.body.dataset.job = job.id;
  $("stop").disabled = false;
  source = new EventSource(withToken("/api/jobs/" + job.id + "/events"));
  source.addEventListener("progress", ev => {
    const d = JSON.parse(ev.data);
    const p = d.progress || {};
    if (d.preview) {
      $("preview").src = d.preview;
      $("preview").dataset.updates = (parseInt($("preview").dataset.updates || "0") + 1);
    }
    setSimilarity(p.best || 0);
    $("stage").textContent = (d.state === "queued" ? "queued" : (p.stage || "starting")) +
      (p.best_shader ? " · " + p.best_shader : "") + (p.evaluations ? " · " + p.evaluations + " renders" : "") +
      (p.elapsed ? " · " + p.elapsed.toFixed(1) + " s" : "");
  });
  source.addEventListener("done", ev => {
    source.close();
    finished(JSON.parse(ev.data));
  });
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) $("stage").textContent += " · connection lost"; };
}

async function finished(status) {
  $("stop").disabled = true;
  if (!status.result) {
    $("stage").textContent = status.state + (status.error ? ": " + status.error : "");
    return;
  }
  const r = status.result;
  spec = r.spec;
  setSimilarity(r.similarity, r.verdict);
  $("verdict-why").textContent = verdictReason(r);
  $("stage").textContent = (status.state === "cancelled" ? "stopped · best so far: " : "done · ") + r.spec.shader + " · " +
    r.evaluations + " renders in " + r.timings.total.toFixed(1) + " s";
  const files = "/api/jobs/" + status.id + "/files/";
  $("preview").src = withToken(files + r.files.render);
  $("dl-compare").href = withToken(files + r.files.compare);
  $("dl-result").href = withToken(files + r.files.result);
  $("to-morph").href = withToken("/morph?job=" + status.id);
  $("to-synth").href = withToken("/synth?job=" + status.id);
  $("shader-name").textContent = spec.shader;
  $("seed").value = spec.seed;
  const decl = await shaderDecl(spec.shader);
  live = new LiveRender($("preview"), $("render-info"), 256);
  buildSliders($("params"), decl, spec.params, params => { spec.params = params; live.request(spec); });
  $("tweak").hidden = false;
  document.body.dataset.done = "1";
}

$("seed").oninput = () => { if (spec) { spec.seed = parseInt($("seed").value) || 0; live.request(spec); } };
$("stop").onclick = async () => {
  if (!job) return;
  $("stop").disabled = true;
  $("stage").textContent = "stopping…";
  try { await api("/api/jobs/" + job.id + "/cancel", { method: "POST" }); } catch (e) { showError($("error"), e); }
};
$("dl-spec").onclick = () => spec && downloadSpec(spec);
$("dl-render").onclick = () => spec && downloadRender(spec, parseInt($("dl-size").value), $("dl-format").value).catch(e => showError($("error"), e));
$("file").onchange = () => $("file").files[0] && start($("file").files[0]);
const drop = $("drop");
drop.ondragover = e => { e.preventDefault(); drop.classList.add("over"); };
drop.ondragleave = () => drop.classList.remove("over");
drop.ondrop = e => { e.preventDefault(); drop.classList.remove("over"); if (e.dataTransfer.files[0]) start(e.dataTransfer.files[0]); };
