// @shader "Scratched surface: random thin scratches over a slightly mottled base"
// @param float density      = 12   [3, 40] log       "Scratch cells across the texture (per layer)"
// @param float length       = 1.5  [0.3, 3]          "Scratch length, in cells"
// @param float width        = 0.004 [0.001, 0.02] log "Scratch width, fraction of the texture"
// @param float direction    = 20   [0, 180]          "Mean scratch direction in degrees"
// @param float randomness   = 0.7  [0, 1]            "Spread of the directions (1: any direction)"
// @param color base_color   = (0.25, 0.26, 0.28)     "Surface colour (linear RGB)"
// @param color scratch_color = (0.70, 0.70, 0.72)    "Scratch colour: lighter or darker (linear RGB)"
// @param float mottle       = 0.3  [0, 1]            "Low-frequency variation of the surface"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float m = pt_fbm(p * 3.0f, fw * 3.0f, 5, 2.0f, 0.5f, pt_subseed(seed, 9u));
  float3 col = P.base_color * (1.0f + P.mottle * 0.5f * m);
  const float a0 = radians(P.direction);
  const float2 mean_dir = (float2)(native_cos(a0), -native_sin(a0));
  for (int layer = 0; layer < 2; ++layer) {
    const uint ls = pt_subseed(seed, (uint)layer);
    const float2 q = p * P.density + 0.5f * (float)layer;
    const float w = fw * P.density;
    const float hw = 0.5f * P.width * P.density;
    const float2 base = pt_floor(q);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int cx = (int)base.x + dx, cy = (int)base.y + dy;
        const float4 f = pt_cell_feature(cx, cy, layer, ls);
        const float len = 0.5f * P.length * (0.3f + 0.7f * f.w);
        const float2 off = q - f.xy;
        if (dot(off, off) > (len + hw + w) * (len + hw + w)) continue;
        const float turn = P.randomness * 3.1f * (f.z - 0.5f);
        float2 dir = mean_dir + turn * (float2)(-mean_dir.y, mean_dir.x);
        dir *= rsqrt(dot(dir, dir));
        // A scratch covers nothing further than its drawn half width + half a pixel from its
        // line: skip the segment distance (exact, and most scratches in reach miss the pixel).
        if (fabs(off.x * dir.y - off.y * dir.x) >= fmax(hw, 0.5f * w) + 0.5f * w) continue;
        const float d = pt_sd_segment(q, f.xy - dir * len, f.xy + dir * len);
        const float cover = pt_line_coverage(d, hw, w);
        const float strength = 0.5f + 0.5f * pt_fract(f.z * 9.7f);
        col = mix(col, P.scratch_color, cover * strength);
      }
  }
  return pt_saturate3(col);
}
