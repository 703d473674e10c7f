// @shader "Sky: vertical gradient from horizon to zenith with perspective clouds and haze"
// @param color zenith_color  = (0.08, 0.20, 0.55)     "Sky colour at the top (linear RGB)"
// @param color horizon_color = (0.55, 0.65, 0.80)     "Sky colour at the horizon (linear RGB)"
// @param color cloud_color   = (0.95, 0.95, 0.95)     "Lit cloud colour (linear RGB)"
// @param float gradient      = 1.0  [0.3, 3] log      "Gradient curve: small keeps the zenith colour low"
// @param float coverage      = 0.35 [0, 0.95]         "Fraction of the sky covered by clouds"
// @param float scale         = 2    [0.5, 8] log      "Cloud features across the top of the image"
// @param float sharpness     = 0.4  [0, 1]            "Cloud edge sharpness"
// @param float horizon       = 1.0  [0.7, 1.3]        "Height of the horizon (1: bottom edge)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float t = clamp((P.horizon - p.y) / P.horizon, 0.0f, 1.0f);  // 0 horizon, 1 top
  const float3 sky = mix(P.horizon_color, P.zenith_color, pt_powr(t, P.gradient));
  if (P.coverage <= 0.0f) return pt_saturate3(sky);
  // Clouds on a plane above the viewer: distance grows towards the horizon.
  const float depth = 1.0f / (fmax(P.horizon - p.y, 0.0f) + 0.12f);
  const float2 q = (float2)((p.x - 0.5f) * depth, depth) * P.scale * 0.5f;
  const float wq = fw * P.scale * 0.5f * depth * depth;
  const float n = pt_fbm(q, wq, 7, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float u = pt_normal_cdf(n / 0.22f);
  const float density = clamp((u - (1.0f - P.coverage)) / fmax(P.coverage, 0.05f), 0.0f, 1.0f);
  const float k = mix(1.5f, 30.0f, P.sharpness * P.sharpness);
  // Distant clouds fade into the haze at the horizon.
  const float alpha = (1.0f - native_exp(-k * density)) * smoothstep(0.0f, 0.25f, t);
  const float3 cloud = mix(P.cloud_color * (1.0f - 0.3f * smoothstep(0.3f, 1.0f, density)), P.horizon_color, 0.5f * (1.0f - t));
  return pt_saturate3(mix(sky, cloud, alpha));
}
