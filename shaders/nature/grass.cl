// @shader "Grass: dense tapered blades in layers, darker deeper down, seen from above"
// @param float density     = 18   [4, 40] log         "Blade cells across the texture (per layer)"
// @param float length      = 1.6  [0.5, 3]            "Blade length, in cells"
// @param float width       = 0.08 [0.03, 0.25] log    "Blade width at the base, in cells"
// @param float direction   = 90   [0, 180]            "Mean blade direction in degrees (90: vertical)"
// @param float randomness  = 0.6  [0, 1]              "Spread of the blade directions (1: any direction)"
// @param color color       = (0.10, 0.25, 0.04)       "Blade colour (linear RGB)"
// @param color tip_color   = (0.35, 0.40, 0.15)       "Colour towards the blade tips (dry tips)"
// @param color ground_color = (0.02, 0.03, 0.01)      "Shadowed ground between blades (linear RGB)"
// @param float variation   = 0.4  [0, 1]              "Blade-to-blade colour variation"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  float3 col = P.ground_color;
  const float a0 = radians(P.direction);
  const float2 mean_dir = (float2)(native_cos(a0), -native_sin(a0));
  // Three layers, deepest first; each layer is darker (shadowed by the ones above).
  for (int layer = 0; layer < 3; ++layer) {
    const uint ls = pt_subseed(seed, (uint)layer);
    const float2 q = p * P.density + (float2)(0.37f, 0.71f) * (float)layer;
    const float w = fw * P.density;
    const float2 base = pt_floor(q);
    const float light = 0.45f + 0.275f * (float)layer;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int cx = (int)base.x + dx, cy = (int)base.y + dy;
        const float4 f = pt_cell_feature(cx, cy, layer, ls);
        const float len = P.length * (0.6f + 0.4f * f.w) * 0.5f;
        const float2 off = q - f.xy;
        if (dot(off, off) > (len + P.width + w) * (len + P.width + w)) continue;  // out of reach
        // Direction: the mean direction turned by a random angle (small-angle rotation, no trig).
        const float turn = P.randomness * 3.1f * (f.z - 0.5f);
        float2 dir = mean_dir + turn * (float2)(-mean_dir.y, mean_dir.x);
        dir *= rsqrt(dot(dir, dir));
        // Far from the blade's centre line the blade cannot cover the pixel (exact, cheap test).
        if (fabs(off.x * dir.y - off.y * dir.x) >= 0.5f * (P.width + w)) continue;
        const float2 a = f.xy - dir * len, b = f.xy + dir * len;
        // Distance along and across the blade; it tapers to a point at b.
        const float2 pa = q - a, ba = b - a;
        const float h = clamp(dot(pa, ba) / dot(ba, ba), 0.0f, 1.0f);
        const float dist = length(pa - ba * h);
        const float half_w = 0.5f * P.width * (1.0f - h);
        const float cover = pt_coverage(dist - half_w, w) * step(0.0f, 1.0f - h);
        if (cover <= 0.0f) continue;  // most blades in reach miss the pixel: skip their colour
        float3 bc = mix(P.color, P.tip_color, h * h);
        bc *= 1.0f + P.variation * (pt_fract(f.z * 11.3f + f.w * 7.1f) - 0.5f);
        // Midrib highlight across the blade.
        bc *= 1.0f + 0.25f * (1.0f - clamp(dist / fmax(half_w, 1e-4f), 0.0f, 1.0f)) * pt_detail_weight(half_w / w);
        col = mix(col, bc * light, cover);
      }
  }
  return pt_saturate3(col);
}
