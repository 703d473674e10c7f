// @shader "Brushed metal: fine anisotropic streaks along a direction or in circles, with soft sheen"
// @param color color      = (0.55, 0.56, 0.58) [0.05, 1] "Metal colour (linear RGB)"
// @param float contrast   = 0.6  [0.1, 1]           "Contrast of the brush streaks"
// @param float scale      = 60   [10, 200] log       "Streaks across the texture"
// @param float stretch    = 30   [4, 100] log        "Streak length / width"
// @param float angle      = 0    [0, 180]            "Brush direction in degrees (linear brushing)"
// @param float sheen      = 0.3  [0, 1]              "Broad bright and dark bands of reflected light"
// @param bool  radial     = false                    "Circular brushing around the centre"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float2 u;
  float jac = 1.0f;  // how much the mapping stretches texture units (for the footprint)
  if (P.radial) {
    const float2 d = p - 0.5f;
    const float r = length(d);
    const float a = pt_atan2(d.y, d.x);
    u = (float2)(a * fmax(r, 0.05f) * 3.0f, r);  // along the circle, across it
    jac = 3.0f;
  } else {
    const float a = radians(P.angle);
    const float2 dir = (float2)(native_cos(a), native_sin(a));
    u = (float2)(dot(p, dir), dot(p, (float2)(-dir.y, dir.x)));
  }
  const float2 q = (float2)(u.x * P.scale / P.stretch, u.y * P.scale);
  const float w = fw * P.scale * jac;
  const float s = pt_fbm(q, w, 5, 2.0f, 0.6f, pt_subseed(seed, 1u));
  // A few stronger individual scratch lines along the brushing.
  const float lines = pt_fbm((float2)(q.x * 0.3f, q.y * 3.0f), w * 3.0f, 2, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float b = pt_fbm(p * 1.5f, fw * 1.5f, 3, 2.0f, 0.5f, pt_subseed(seed, 3u));
  float3 c = P.color * (1.0f + P.contrast * (0.6f * s + 0.4f * lines) + P.sheen * 0.5f * b);
  return pt_saturate3(c);
}
