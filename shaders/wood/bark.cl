// @shader "Tree bark: vertical plates split by deep furrows, with fibres and lichen patches"
// @param float scale        = 7    [2, 20] log         "Plates across the texture"
// @param float stretch      = 4    [1, 10] log         "Vertical elongation of the ridges"
// @param float depth        = 0.7  [0, 1]              "Darkness of the furrows"
// @param float furrow_width = 0.25 [0.05, 0.6]        "Width of the furrows, fraction of a plate"
// @param color bark_color   = (0.22, 0.16, 0.11)      "Ridge colour (linear RGB)"
// @param color furrow_color = (0.04, 0.03, 0.02)      "Furrow colour (linear RGB)"
// @param float lichen       = 0.1  [0, 1]              "Coverage of lichen patches"
// @param color lichen_color = (0.35, 0.40, 0.28)      "Lichen colour (linear RGB)"
// @param float roughness    = 0.5  [0, 1]              "Fine cracks and texture on the ridges"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  // Bark plates: Voronoi cells squeezed vertically, separated by wide furrows.
  float2 q = (float2)(p.x, p.y / P.stretch) * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.2f, 1.5f, 2, pt_subseed(seed, 4u));
  const PtVoronoi v = pt_voronoi(q, 1.0f, seed);
  const float d = 0.5f * P.furrow_width - v.edge;
  const float plate = pt_coverage(d, w);
  const float dome = smoothstep(0.0f, 0.3f, -d);
  float3 c = pt_vary_color(P.bark_color, 0.3f, v.id, 0.5f) * (0.6f + 0.4f * dome);
  // Vertical fibres and cracks on the plates.
  const float n = pt_fbm((float2)(q.x * 6.0f, q.y * 1.5f), w * 6.0f, 4, 2.0f, 0.6f, pt_subseed(seed, 2u));
  c *= 1.0f + P.roughness * 0.6f * n;
  const float3 fc = P.furrow_color * (1.0f + 0.5f * n);
  c = mix(mix(c, fc, P.depth), c, plate);
  const float l = pt_fbm(p * 5.0f, fw * 5.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  const float cov = pt_aa_threshold(l, 0.5f - 1.0f * P.lichen, 0.08f, fw * 5.0f * 2.0f) * plate;
  c = mix(c, P.lichen_color * (1.0f + 0.4f * n), cov * step(0.001f, P.lichen));
  return pt_saturate3(c);
}
