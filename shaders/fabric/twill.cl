// @shader "Twill weave (denim, gabardine): diagonal ribs from warp threads floating over several wefts"
// @param int   threads      = 32   [8, 96]             "Threads along each side of the texture"
// @param int   period       = 4    [3, 8]              "Repeat of the weave in threads (3: 2/1 twill, 4: 2/2 or 3/1)"
// @param int   over         = 3    [1, 7]              "Wefts each warp floats over per repeat (clamped below the period)"
// @param float gap          = 0.08 [0.0, 0.5]          "Gap between threads, fraction of the spacing"
// @param color warp_color   = (0.05, 0.10, 0.30)       "Warp (vertical) thread colour; indigo for denim"
// @param color weft_color   = (0.70, 0.68, 0.62)       "Weft (horizontal) thread colour"
// @param color gap_color    = (0.02, 0.02, 0.03)       "Colour seen through the gaps"
// @param float relief       = 0.5  [0, 1]              "Shading of the round threads"
// @param float fibre        = 0.5  [0, 1]              "Fibre streaks and slub along the threads"
// @param float fading       = 0.2  [0, 1]              "Large-scale washed-out patches (worn denim)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.threads;
  const float2 q = p * n;
  const float w = fw * n;
  const float2 cell = pt_floor(q);
  const float2 f = q - cell - 0.5f;
  const int i = (int)cell.x, j = (int)cell.y;
  const int over = min(P.over, P.period - 1);
  int m = (i + j) % P.period;
  if (m < 0) m += P.period;
  const int warp_on_top = m < over;
  const float rw = pt_rand(i, 0, 7, seed), rf = pt_rand(0, j, 8, seed);
  const float nw = pt_fbm((float2)(q.x * 10.0f, q.y * 0.8f), w * 10.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 1u));
  const float nf = pt_fbm((float2)(q.x * 0.8f, q.y * 10.0f), w * 10.0f, 3, 2.0f, 0.5f, pt_subseed(seed, 2u));
  const float fade = pt_fbm(p * 3.0f, fw * 3.0f, 4, 2.0f, 0.5f, pt_subseed(seed, 3u));
  float3 warp = P.warp_color * (1.0f + 0.5f * P.fibre * nw + 0.3f * P.fibre * (rw - 0.5f));
  warp = mix(warp, P.weft_color, P.fading * clamp(0.3f + fade, 0.0f, 1.0f) * 0.6f);
  const float3 weft = P.weft_color * (1.0f + 0.4f * P.fibre * nf + 0.2f * P.fibre * (rf - 0.5f));
  const float h = 0.5f * (1.0f - P.gap);
  return pt_saturate3(pt_weave_cell(f, w, h, h, warp_on_top, P.relief, warp, weft, P.gap_color));
}
