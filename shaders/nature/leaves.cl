// @shader "Fallen leaves: overlapping pointed leaves of varied colour and orientation on the ground"
// @param float density     = 8    [3, 30] log         "Leaf cells across the texture (two leaves per cell)"
// @param float size        = 0.7  [0.3, 1.6]          "Leaf length, in cells (large: dense overlapping foliage)"
// @param float elongation  = 2.2  [1.2, 4]            "Leaf length / width"
// @param color color       = (0.45, 0.20, 0.03)       "Main leaf colour (linear RGB)"
// @param color color2      = (0.50, 0.40, 0.05)       "Second leaf colour, mixed per leaf (linear RGB)"
// @param color ground_color = (0.05, 0.04, 0.03)      "Ground colour between leaves (linear RGB)"
// @param float variation   = 0.3  [0, 1]              "Leaf-to-leaf brightness variation"
// @param float veins       = 0.5  [0, 1]              "Visibility of the midrib and side veins"
// @param float shading     = 0.3  [0, 1]              "Light and shadow: leaves lit on one side, lower leaves darker (foliage, ivy)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float2 q = p * P.density;
  const float w = fw * P.density;
  const float2 base = pt_floor(q);
  float3 col = P.ground_color * (1.0f + 0.5f * pt_fbm(q * 2.0f, w * 2.0f, 3, 2.0f, 0.5f, seed));
  // Paint leaves bottom to top: a leaf's random depth decides the order, so find for each pixel
  // the covering leaf with the highest depth (leaves reach at most one cell beyond their own).
  float top = -1.0f;
  const float hl = 0.5f * P.size, hw = hl / P.elongation;
  // Leaves within reach (hl + w) of q have their centres in the 3x3 cells around q; when the reach
  // is at most half a cell, in the 2x2 cells nearest q. Visiting that sub-window in the same order
  // gives the same pixels (leaves out of reach change nothing) at 8 instead of 18 leaf lookups.
  const int n = hl + w <= 0.5f ? 2 : 3;
  const int x0 = n == 2 ? (int)pt_floor(q.x - 0.5f) : (int)base.x - 1;
  const int y0 = n == 2 ? (int)pt_floor(q.y - 0.5f) : (int)base.y - 1;
  for (int dy = 0; dy < n; ++dy)
    for (int dx = 0; dx < n; ++dx)
      for (int k = 0; k < 2; ++k) {
        const int cx = x0 + dx, cy = y0 + dy;
        const float4 f = pt_cell_feature(cx, cy, k, seed);
        const float depth = pt_fract(f.z * 7.13f + f.w * 3.1f);
        if (depth <= top) continue;
        const float2 d = q - f.xy;
        if (dot(d, d) > (hl + w) * (hl + w)) continue;  // out of reach
        const float2 dir = normalize((float2)(f.z, pt_fract(f.w * 5.3f)) - 0.5f + 1e-4f);
        const float2 l = (float2)(d.x * dir.y - d.y * dir.x, dot(d, dir));  // y along the leaf
        const float s = pt_sd_leaf(l, hl, hw);
        const float cover = pt_coverage(s, w);
        if (cover <= 0.0f) continue;
        float3 lc = mix(P.color, P.color2, f.w);
        lc *= 1.0f + P.variation * (f.z - 0.5f);
        // Midrib and side veins, faded when finer than a pixel.
        const float dv = pt_detail_weight(0.1f * hw / w);
        const float mid = 1.0f - pt_filtered_pulse(-0.03f * hw, 0.03f * hw, l.x, w);
        const float side = pt_filtered_pulsetrain(0.12f, (l.y - 0.8f * fabs(l.x)) * (5.0f / hl), w * 5.0f / hl);
        lc *= 1.0f - P.veins * dv * (0.35f * (1.0f - mid) + 0.15f * side);
        // Shading: each leaf curves away from its midrib (one half catches the light) and the
        // lower ones lie in the upper ones' shade - what gives a hedge or ivy its depth.
        lc *= 1.0f + P.shading * (0.45f * clamp(l.x / hw, -1.0f, 1.0f) - 0.6f * (1.0f - depth));
        // Shadow of the leaf's own rim onto the leaves below.
        col = mix(col * 0.7f, lc, cover) * cover + col * (1.0f - cover);
        if (cover > 0.5f) top = depth;
      }
  return pt_saturate3(col);
}
