// @shader "Animal coat spots: leopard rosettes, cheetah spots or giraffe patches"
// @param float scale        = 7    [3, 30] log        "Spots across the texture"
// @param enum  kind         = leopard {leopard, cheetah, giraffe} "Spot pattern"
// @param float size         = 0.75 [0.2, 1]         "Spot size (giraffe: patch size versus the light network)"
// @param float irregularity = 0.5  [0, 1]             "Irregular, broken spot outlines"
// @param color fur_color    = (0.65, 0.42, 0.15)      "Base fur colour (linear RGB)"
// @param color spot_color   = (0.04, 0.03, 0.02)      "Spot colour (linear RGB)"
// @param color center_color = (0.45, 0.25, 0.08)      "Rosette centre colour (leopard; linear RGB)"
// @param float fur          = 0.3  [0, 1]             "Fur streak texture"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 q = p * P.scale;
  const float w = fw * P.scale;
  q = pt_warp(q, w, 0.25f * P.irregularity, 1.2f, 2, pt_subseed(seed, 1u));
  const float n = pt_fbm(q * 2.5f, w * 2.5f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const PtVoronoi v = pt_voronoi(q, 0.9f, seed);
  float3 c = P.fur_color;
  if (P.kind == KIND_GIRAFFE) {
    // Dark polygonal patches separated by a light network.
    const float d = 0.5f * (1.0f - P.size) * 0.6f - v.edge + 0.05f * P.irregularity * n;
    c = mix(P.fur_color, P.spot_color * (1.0f + 0.3f * n), pt_coverage(d, w));
  } else if (P.kind == KIND_CHEETAH) {
    const float r = 0.38f * P.size * (0.7f + 0.6f * v.id);
    const float d = v.f1 - r + 0.08f * P.irregularity * n;
    c = mix(P.fur_color, P.spot_color, pt_coverage(d, w));
  } else {
    // Rosette: a broken ring around a slightly darker centre.
    const float R = 0.45f * P.size * (0.8f + 0.4f * v.id);
    const float thick = 0.35f * R;
    const float ring = fabs(v.f1 - R) - 0.5f * thick + 0.06f * P.irregularity * n;
    // Breaks: the ring is interrupted where angular noise is high.
    const float2 dir = (q - v.point) / fmax(v.f1, 1e-4f);
    const float gap = pt_gnoise(dir * 2.2f + v.id * 17.0f, pt_subseed(seed, 3u));
    const float broken = pt_aa_threshold(gap, 0.65f - 0.5f * P.irregularity, 0.1f, 0.0f);
    const float centre = pt_coverage(v.f1 - R, w);
    c = mix(c, P.center_color, centre);
    c = mix(c, P.spot_color, pt_coverage(ring, w) * (1.0f - broken));
  }
  const float s = pt_fbm((float2)(p.x * 30.0f, p.y * 120.0f), fw * 120.0f, 2, 2.0f, 0.5f, pt_subseed(seed, 4u));
  c *= 1.0f + P.fur * 0.4f * s + 0.1f * n;
  return pt_saturate3(c);
}
