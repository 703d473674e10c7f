// Woven cloth: one crossing of a warp (vertical) and a weft (horizontal) thread, shared by the
// plain weave, twill and burlap shaders. f: position in the crossing cell, [-0.5, 0.5)^2; w: the
// pixel footprint in cell units; half widths of the two threads (cell units); which is on top;
// thread colours (already varied and fibre-textured) and the colour seen through the gaps.

// Shading of one thread: x across it in [-1, 1], t along the crossing in [-1, 1]; fades to its
// mean once a cell spans under ~4 pixels (dw).
float pt_thread_shade(float x, float t, float relief, float dw) {
  const float across = mix(0.6667f, 1.0f - x * x, dw);
  const float along = mix(0.8333f, 1.0f - 0.5f * t * t, dw);
  return mix(1.0f, across * along, relief);
}

float3 pt_weave_cell(float2 f, float w, float half_warp, float half_weft, int warp_on_top,
                     float relief, float3 warp, float3 weft, float3 gap_color) {
  const float dw = pt_detail_weight(1.0f / w);
  const float cov_warp = pt_coverage(fabs(f.x) - half_warp, w);
  const float cov_weft = pt_coverage(fabs(f.y) - half_weft, w);
  warp *= pt_thread_shade(f.x / half_warp, 2.0f * f.y, relief, dw);
  weft *= pt_thread_shade(f.y / half_weft, 2.0f * f.x, relief, dw);
  // The top thread covers the bottom one; the bottom one shows beside it, dipping (darker).
  const float dip = 1.0f - 0.45f * relief;
  if (warp_on_top) return mix(mix(gap_color, weft * dip, cov_weft), warp, cov_warp);
  return mix(mix(gap_color, warp * dip, cov_warp), weft, cov_weft);
}
