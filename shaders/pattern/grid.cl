// @shader "Grid of major and minor lines on a background (graph paper, tile layouts)"
// @param int   cells          = 8    [1, 32]          "Major cells along each side of the texture"
// @param float width          = 0.05 [0.005, 0.3] log "Major line width, fraction of a cell"
// @param int   subdivisions   = 1    [1, 8] needs=minor_strength "Minor cells per major cell (1: no minor lines)"
// @param float minor_width    = 0.4  [0.05, 1] needs=minor_strength "Minor line width relative to the major lines"
// @param float minor_strength = 0.5  [0, 1]           "Opacity of the minor lines"
// @param color line_color     = (0.05, 0.12, 0.35)    "Line colour (linear RGB)"
// @param color background     = (0.90, 0.90, 0.86)    "Background colour (linear RGB)"

// Coverage of lines of the given width (period units) centred on integer positions of q.
float grid_lines(float2 q, float width, float w) {
  const float a = pt_filtered_pulsetrain(width, q.x + 0.5f * width, w);
  const float b = pt_filtered_pulsetrain(width, q.y + 0.5f * width, w);
  return a + b - a * b;
}

float3 shade(float2 p, float fw, uint seed, const Params P) {
  const float n = (float)P.cells;
  float cover = grid_lines(p * n, P.width, fw * n);
  if (P.subdivisions > 1) {
    const float m = n * (float)P.subdivisions;
    const float mw = fmin(P.width * P.minor_width * (float)P.subdivisions, 0.4f);
    const float minor = P.minor_strength * grid_lines(p * m, mw, fw * m);
    cover = cover + minor - cover * minor;
  }
  return mix(P.background, P.line_color, cover);
}
