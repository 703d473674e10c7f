// @shader "Cellular stones: irregular stones with per-stone colour, rounded shading and gaps"
// @param float scale      = 7    [2, 30] log          "Stones across the texture"
// @param float jitter     = 0.9  [0, 1]               "Irregularity of the stone layout"
// @param float gap        = 0.08 [0.01, 0.4] log      "Gap between stones, fraction of a stone"
// @param color stone_color = (0.45, 0.42, 0.38)       "Mean stone colour (linear RGB)"
// @param color gap_color  = (0.08, 0.07, 0.06)        "Gap / mortar colour (linear RGB)"
// @param float variation  = 0.4  [0, 1]               "Stone-to-stone colour variation"
// @param float roundness  = 0.5  [0, 1]               "Darkening towards the stone edges (rounded stones)"
// @param float roughness  = 0.3  [0, 1]               "Surface speckle"
// @param float warp       = 0.3  [0, 1]               "Wobble of the stone outlines"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.25f * P.warp, 1.5f, 3, pt_subseed(seed, 1u));
  const PtVoronoi v = pt_voronoi(q, P.jitter, seed);
  const float d = 0.5f * P.gap - v.edge;  // negative inside the stone
  const float cover = pt_coverage(d, w);

  const float r2 = pt_rand(v.cell.x, v.cell.y, 3, seed);
  float3 sc = pt_vary_color(P.stone_color, P.variation, v.id, r2);
  const float rim = smoothstep(0.0f, 0.35f, -d);
  sc *= mix(1.0f, 0.45f + 0.55f * sqrt(rim), P.roundness);
  const float n = pt_fbm(q * 4.0f, w * 4.0f, 4, 2.0f, 0.6f, pt_subseed(seed, 2u));
  sc *= 1.0f + P.roughness * 0.6f * n;
  const float3 gc = P.gap_color * (1.0f + 0.3f * n);
  return pt_saturate3(mix(gc, sc, cover));
}
