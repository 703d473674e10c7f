// @shader "A centred n-pointed star on a background"
// @param int   points   = 5    [3, 12]              "Number of points"
// @param float size     = 0.8  [0.1, 0.98]          "Outer diameter, fraction of the texture"
// @param float inner    = 0.45 [0.1, 0.95]          "Inner radius / outer radius (1 would be a polygon)"
// @param float rotation = 0    [0, 180] period=360/points "Rotation in degrees (0: a point straight up)"
// @param float softness = 0    [0, 0.5]             "Edge blur, fraction of the shape size"
// @param color fg       = (0.95, 0.75, 0.10)        "Star colour (linear RGB)"
// @param color bg       = (0.05, 0.10, 0.30)        "Background colour (linear RGB)"

float3 shade(float2 p, float fw, uint seed, const Params P) {
  // Screen y points down: the first point along -y is straight up.
  float2 q = p - 0.5f;
  q = pt_rotate((float2)(q.x, -q.y), -radians(P.rotation) - 0.5f * M_PI_F);
  const float d = pt_sd_star(q, 0.5f * P.size, P.points, P.inner);
  return mix(P.bg, P.fg, pt_coverage(d, fw + P.softness * P.size));
}
