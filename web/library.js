// Library page: every shader, its parameters as sliders, a live render, the seed.
"use strict";
nav("Library");
const $ = id => document.getElementById(id);
const live = new LiveRender($("render"), $("render-info"), 384);
let spec = null;

async function select(name) {
  const decl = await shaderDecl(name);
  if (!decl) return showError($("error"), "no shader " + name);
  for (const a of document.querySelectorAll(".list a")) a.classList.toggle("active", a.textContent === name);
  $("title").textContent = decl.name + " · " + decl.family;
  $("help").textContent = decl.help;
  spec = { shader: name, params: {}, seed: parseInt($("seed").value) || 0 };
  spec.params = buildSliders($("params"), decl, null, params => { spec.params = params; live.request(spec); });
  $("to-morph").href = withToken("/morph?key=" + encodeURIComponent(JSON.stringify(spec)));
  history.replaceState(null, "", withToken("/library?shader=" + name));
  live.request(spec);
}

(async () => {
  try {
    const list = await shaders();
    let family = "";
    for (const s of list) {
      if (s.family !== family) {
        family = s.family;
        const f = document.createElement("div");
        f.className = "family";
        f.textContent = family;
        $("list").appendChild(f);
      }
      const a = document.createElement("a");
      a.textContent = s.name;
      a.title = s.help;
      a.onclick = () => select(s.name);
      $("list").appendChild(a);
    }
    select(new URLSearchParams(location.search).get("shader") || list[0].name);
  } catch (e) { showError($("error"), e); }
})();

$("seed").oninput = () => { if (spec) { spec.seed = parseInt($("seed").value) || 0; live.request(spec); } };
$("reset").onclick = () => spec && select(spec.shader);
$("dl-spec").onclick = () => spec && downloadSpec(spec);
$("dl-render").onclick = () => spec && downloadRender(spec, parseInt($("dl-size").value), $("dl-format").value).catch(e => showError($("error"), e));
$("to-morph").onclick = () => { $("to-morph").href = withToken("/morph?key=" + encodeURIComponent(JSON.stringify(spec))); };
