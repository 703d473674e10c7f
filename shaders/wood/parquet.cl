// @shader "Parquet: basket-weave blocks of short wooden strips alternating in direction"
// @param int   blocks      = 4    [2, 8]              "Blocks along each side of the texture"
// @param int   strips      = 4    [2, 8]               "Strips per block"
// @param float gap         = 0.03 [0.005, 0.15] log    "Gap between strips, fraction of a strip width"
// @param float rings       = 3    [1, 20] log          "Growth rings per strip width"
// @param float grain       = 0.4  [0, 1]               "Fine grain streaks"
// @param float variation   = 0.3  [0, 1]               "Strip-to-strip colour variation"
// @param color light_color = (0.55, 0.35, 0.17)        "Early wood colour (linear RGB)"
// @param color dark_color  = (0.32, 0.17, 0.07)        "Late wood colour (linear RGB)"
// @param color gap_color   = (0.05, 0.03, 0.02)        "Gap colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float nb = (float)P.blocks, ns = (float)P.strips;
  const float2 q = p * nb;
  const float2 b = pt_floor(q);
  const float2 f = q - b;
  const int vert = (((int)b.x + (int)b.y) & 1);
  // Position in strip units: along the strip (x) and across (y).
  const float2 s = (vert ? (float2)(f.y, f.x) : f) * ns;
  const float k = pt_floor(s.y);
  const float2 lp = (float2)(s.x - 0.5f * ns, s.y - k - 0.5f);
  const float w = fw * nb * ns;
  const float d = pt_sd_box(lp, (float2)(0.5f * ns, 0.5f) - 0.5f * P.gap);
  const float cover = pt_coverage(d, w);
  const int ix = (int)b.x * 16 + (int)k, iy = (int)b.y;
  const float4 r = pt_cell_feature(ix, iy, 0, seed);
  const float2 a = (float2)((lp.x + 5.0f * r.x) / 4.0f, lp.y - 0.8f - 2.0f * r.z) / (nb * ns);
  float3 col = pt_wood(a, fw, P.rings * nb * ns, 0.4f, 0.35f, 0.5f, P.grain, P.light_color, P.dark_color,
                       pt_hash3(ix, iy, 13, seed));
  col = pt_vary_color(col, P.variation, r.w, r.y - pt_floor(r.y));
  return pt_saturate3(mix(P.gap_color, col, cover));
}
