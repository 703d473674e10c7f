// @shader "Plain weave cloth: warp and weft threads passing over and under each other"
// @param int   threads      = 24   [4, 96]             "Threads along each side of the texture"
// @param float gap          = 0.15 [0.0, 0.6]          "Gap between threads, fraction of the spacing"
// @param color warp_color   = (0.55, 0.50, 0.40)       "Colour of the vertical (warp) threads"
// @param color weft_color   = (0.45, 0.40, 0.32)       "Colour of the horizontal (weft) threads"
// @param color gap_color    = (0.04, 0.035, 0.03)      "Colour seen through the gaps"
// @param float relief       = 0.6  [0, 1]              "Shading of the round threads and their dips"
// @param float fibre        = 0.4  [0, 1]              "Fibre streaks along each thread"
// @param float irregularity = 0.3  [0, 1]              "Thread-to-thread colour and thickness variation"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.threads;
  const float2 q = p * n;
  const float w = fw * n;
  const float2 cell = pt_floor(q);
  const float2 f = q - cell - 0.5f;  // [-0.5, 0.5)
  const int i = (int)cell.x, j = (int)cell.y;
  const int warp_on_top = ((i + j) & 1) == 0;

  // Per-thread random thickness and colour (warp threads by column, weft threads by row).
  const float rw = pt_rand(i, 0, 7, seed), rf = pt_rand(0, j, 8, seed);
  const float half_w_warp = 0.5f * (1.0f - P.gap) * (1.0f - 0.25f * P.irregularity * rw);
  const float half_w_weft = 0.5f * (1.0f - P.gap) * (1.0f - 0.25f * P.irregularity * rf);
  // Fibres: noise stretched along each thread.
  const float nw = pt_fbm((float2)(q.x * 10.0f, q.y * 1.2f), w * 10.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float nf = pt_fbm((float2)(q.x * 1.2f, q.y * 10.0f), w * 10.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  float3 warp = pt_vary_color(P.warp_color, 0.3f * P.irregularity, rw, pt_rand(i, 0, 9, seed));
  float3 weft = pt_vary_color(P.weft_color, 0.3f * P.irregularity, rf, pt_rand(0, j, 10, seed));
  warp *= 1.0f + 0.5f * P.fibre * nw;
  weft *= 1.0f + 0.5f * P.fibre * nf;
  return pt_saturate3(pt_weave_cell(f, w, half_w_warp, half_w_weft, warp_on_top, P.relief, warp, weft,
                                    P.gap_color));
}
