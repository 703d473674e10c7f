// @shader "Wooden floor planks: boards with their own grain, staggered end joints and dark gaps"
// @param int   planks      = 6    [2, 20]              "Boards across the texture"
// @param float length      = 5    [1.5, 16] log        "Board length / board width"
// @param float gap         = 0.04 [0.005, 0.2] log     "Gap between boards, fraction of a board width"
// @param float rings       = 10   [2, 40] log          "Growth rings per board width"
// @param float distortion  = 0.4  [0, 1]               "Wobble of the rings"
// @param float grain       = 0.4  [0, 1]               "Fine grain streaks"
// @param float variation   = 0.25 [0, 1]               "Board-to-board colour variation"
// @param color light_color = (0.50, 0.30, 0.14)        "Early wood colour (linear RGB)"
// @param color dark_color  = (0.28, 0.13, 0.05)        "Late wood colour (linear RGB)"
// @param color gap_color   = (0.03, 0.02, 0.01)        "Gap colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.planks;
  const float2 q = p * n;  // one board is 1 unit wide
  const float w = fw * n;
  const float row = pt_floor(q.y);
  const float shift = pt_rand(0, (int)row, 3, seed) * P.length;
  const float4 c = pt_brick_cell((float2)(q.x + shift, q.y), P.length, 0.0f);
  const int cx = (int)c.x, cy = (int)c.y;
  const float2 lp = c.zw - (float2)(0.5f * P.length, 0.5f);
  const float d = pt_sd_box(lp, (float2)(0.5f * P.length, 0.5f) - 0.5f * P.gap);
  const float cover = pt_coverage(d, w);
  // Each board is cut from its own log: random pith depth and offset.
  const float4 r = pt_cell_feature(cx, cy, 0, seed);
  const float2 a = (float2)((lp.x + 7.0f * r.x) / (3.0f * P.length), lp.y - 0.6f - 1.5f * r.z) / n;
  float3 col = pt_wood(a, fw * 1.0f, P.rings * n, P.distortion, 0.35f, 0.5f, P.grain, P.light_color,
                       P.dark_color, pt_hash3(cx, cy, 11, seed));
  col = pt_vary_color(col, P.variation, r.w, r.y - pt_floor(r.y));
  return pt_saturate3(mix(P.gap_color, col, cover));
}
