// proctex web UI: shared helpers (API calls with the optional token, parameter sliders, live renders).
"use strict";
const token = new URLSearchParams(location.search).get("token");

function withToken(url) {
  if (!token) return url;
  return url + (url.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(token);
}

async function api(path, options = {}) {
  const headers = Object.assign({}, options.headers || {});
  if (token) headers["Authorization"] = "Bearer " + token;
  const res = await fetch(path, Object.assign({}, options, { headers }));
  if (!res.ok) {
    let msg = res.status + " " + res.statusText;
    try { const j = await res.json(); msg = j.error + (j.hint ? " (" + j.hint + ")" : ""); } catch (e) {}
    const err = new Error(msg);
    err.status = res.status;
    throw err;
  }
  return res;
}
const apiJson = async (path, options) => (await api(path, options)).json();

function showError(el, e) { el.textContent = e ? String(e.message || e) : ""; }

function nav(active) {
  const links = [["/", "Match"], ["/library", "Library"], ["/morph", "Morph"], ["/synth", "Synth"]];
  const header = document.createElement("header");
  header.innerHTML = '<h1>proctex</h1><nav></nav><span class="status" id="health"></span>';
  for (const [href, name] of links) {
    const a = document.createElement("a");
    a.href = withToken(href);
    a.textContent = name;
    if (name === active) a.className = "active";
    header.querySelector("nav").appendChild(a);
  }
  document.body.prepend(header);
  apiJson("/api/health").then(h => {
    document.getElementById("health").textContent = "proctex " + h.version + " · " + h.device +
      (h.catalog_present ? "" : " · no catalogue: match and morph unavailable");
  }).catch(e => { document.getElementById("health").textContent = String(e.message); });
}

let shaderCache = null;
async function shaders() {
  if (!shaderCache) shaderCache = await apiJson("/api/shaders");
  return shaderCache;
}
async function shaderDecl(name) { return (await shaders()).find(s => s.name === name); }

// sRGB <-> linear for colour pickers (spec colours are linear RGB).
const toLinear = c => c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4);
const toSrgb = c => c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055;
function linearToHex(rgb) {
  return "#" + rgb.map(v => Math.round(255 * Math.min(1, Math.max(0, toSrgb(v)))).toString(16).padStart(2, "0")).join("");
}
function hexToLinear(hex) {
  return [1, 3, 5].map(i => toLinear(parseInt(hex.substr(i, 2), 16) / 255));
}

// Builds one control per parameter of `decl` into `box`; calls onChange(params) on every move.
// Values start from `values` (a spec's params), else the defaults.
function buildSliders(box, decl, values, onChange) {
  box.innerHTML = "";
  const params = {};
  for (const p of decl.params) {
    const v = values && p.name in values ? values[p.name] : p.default;
    params[p.name] = v;
    const row = document.createElement("div");
    row.className = "param";
    row.title = p.help;
    const label = document.createElement("label");
    label.textContent = p.name;
    const out = document.createElement("span");
    out.className = "value";
    let input;
    if (p.type === "bool") {
      input = document.createElement("input");
      input.type = "checkbox";
      input.checked = !!v;
      input.oninput = () => { params[p.name] = input.checked; out.textContent = input.checked; onChange(params); };
      out.textContent = !!v;
    } else if (p.type === "enum") {
      input = document.createElement("select");
      for (const name of p.values) input.add(new Option(name, name));
      input.value = v;
      input.oninput = () => { params[p.name] = input.value; onChange(params); };
    } else if (p.type === "color") {
      input = document.createElement("input");
      input.type = "color";
      input.value = linearToHex(v);
      input.oninput = () => { params[p.name] = hexToLinear(input.value); out.textContent = input.value; onChange(params); };
      out.textContent = input.value;
    } else {
      const [lo, hi] = p.range;
      const log = p.scale === "log" && lo > 0;
      const toSlider = x => log ? Math.log(x / lo) / Math.log(hi / lo) : (x - lo) / (hi - lo);
      const fromSlider = t => log ? lo * Math.pow(hi / lo, t) : lo + t * (hi - lo);
      input = document.createElement("input");
      input.type = "range";
      input.dataset.param = p.name;
      if (p.type === "int") { input.min = lo; input.max = hi; input.step = 1; input.value = v; }
      else { input.min = 0; input.max = 1; input.step = 0.001; input.value = toSlider(v); }
      const show = x => out.textContent = p.type === "int" ? String(x) : Number(x).toPrecision(3);
      show(v);
      input.oninput = () => {
        const x = p.type === "int" ? parseInt(input.value) : fromSlider(parseFloat(input.value));
        params[p.name] = x;
        show(x);
        onChange(params);
      };
    }
    row.append(label, input, out);
    box.appendChild(row);
  }
  return params;
}

// Live renders: at most one request in flight; moves made meanwhile collapse into the latest.
class LiveRender {
  constructor(img, info, size = 256) { this.img = img; this.info = info; this.size = size; this.busy = false; this.next = null; this.count = 0; }
  request(spec) {
    this.next = JSON.parse(JSON.stringify(spec));
    if (!this.busy) this.pump();
  }
  async pump() {
    this.busy = true;
    while (this.next) {
      const spec = this.next;
      this.next = null;
      const t0 = performance.now();
      try {
        const res = await api("/api/render", { method: "POST", headers: { "Content-Type": "application/json" },
                                               body: JSON.stringify({ spec, size: this.size }) });
        const blob = await res.blob();
        const old = this.img.src;
        this.img.src = URL.createObjectURL(blob);
        if (old.startsWith("blob:")) URL.revokeObjectURL(old);
        this.count++;
        this.img.dataset.renders = this.count;
        if (this.info) this.info.textContent = "render " + Math.round(performance.now() - t0) + " ms (server " + res.headers.get("X-Render-Milliseconds") + " ms)";
      } catch (e) {
        if (this.info) this.info.textContent = e.message;
      }
    }
    this.busy = false;
  }
}

function download(name, blob) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}

async function downloadRender(spec, size, format) {
  const res = await api("/api/render", { method: "POST", headers: { "Content-Type": "application/json" },
                                         body: JSON.stringify({ spec, size, format }) });
  download(spec.shader + "-" + size + "." + format, await res.blob());
}

function downloadSpec(spec) {
  download(spec.shader + ".json", new Blob([JSON.stringify(spec, null, 2) + "\n"], { type: "application/json" }));
}
