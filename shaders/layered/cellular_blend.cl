// @shader "Cellular pattern blended with noise through a colour ramp: cells, cracks, blobs, flakes"
// @param enum  feature   = edge {f1, edge, cell}  "Cellular feature: distance to points, to borders, or flat cells"
// @param float scale     = 8    [2, 24] log      "Cells across the texture"
// @param float jitter    = 0.9  [0, 1]           "Irregularity of the cell layout"
// @param float noise     = 0.4  [0, 1]           "Blend of fBm noise into the value"
// @param float noise_scale = 2  [0.5, 8] log     "fBm frequency relative to the cells"
// @param float contrast  = 0.5  [0, 1]           "Contrast of the ramp lookup"
// @param float invert    = 0    [0, 1]           "Flip the cellular value (0 normal, 1 inverted)"
// @param color color_a   = (0.05, 0.04, 0.03)    "Ramp colour for low values (linear RGB)"
// @param color color_b   = (0.40, 0.30, 0.20)    "Ramp colour for middle values (linear RGB)"
// @param color color_c   = (0.85, 0.75, 0.60)    "Ramp colour for high values (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.scale;
  const float w = fw * P.scale;
  float v;
  if (P.feature == FEATURE_EDGE) {
    const PtCellular c = pt_cellular(q, P.jitter, seed);
    // Half of F2 - F1 approximates the border distance; smoothed by the footprint.
    v = clamp(0.5f * (c.f2 - c.f1) * 2.0f, 0.0f, 1.0f);
    v = mix(0.35f, v, pt_detail_weight(0.5f / w));
  } else if (P.feature == FEATURE_CELL) {
    const PtCellular c = pt_cellular(q, P.jitter, seed);
    const float border = clamp(0.5f * (c.f2 - c.f1) / fmax(w, 1e-6f) + 0.5f, 0.0f, 1.0f);
    v = mix(0.5f, c.id, border * pt_detail_weight(1.0f / w));
  } else {
    const PtCellular c = pt_cellular(q, P.jitter, seed);
    v = clamp(1.0f - c.f1, 0.0f, 1.0f);
    v = mix(0.5f, v, pt_detail_weight(0.7f / w));
  }
  v = mix(v, 1.0f - v, P.invert);
  const float n = pt_fbm(q * P.noise_scale, w * P.noise_scale, 5, 2.0f, 0.5f, pt_subseed(seed, 1u));
  v = v + P.noise * 0.8f * n;
  const float k = mix(0.7f, 3.0f, P.contrast);
  const float t = clamp(0.5f + (v - 0.45f) * k, 0.0f, 1.0f);
  return pt_ramp3(t, P.color_a, P.color_b, P.color_c);
}
