// Filtered pattern primitives: steps and pulses integrated over the pixel footprint, so hard
// edges antialias analytically instead of aliasing (Advanced RenderMan, ch. 11).

// Step from 0 to 1 at `edge`, box-filtered over width w.
float pt_filtered_step(float edge, float x, float w) {
  w = fmax(w, 1e-6f);
  return clamp((x - edge) / w + 0.5f, 0.0f, 1.0f);
}

// 1 inside [a, b), 0 outside, box-filtered over width w.
float pt_filtered_pulse(float a, float b, float x, float w) {
  return pt_filtered_step(a, x, w) - pt_filtered_step(b, x, w);
}

// Integral of a unit-period pulse train that is 1 on [0, duty) of each period.
float pt_pulsetrain_integral(float x, float duty) {
  const float n = floor(x);
  return n * duty + fmin(x - n, duty);
}

// Periodic pulse train (period 1, 1 on [0, duty)) box-filtered over width w: exact area average.
float pt_filtered_pulsetrain(float duty, float x, float w) {
  w = fmax(w, 1e-6f);
  const float x0 = x - 0.5f * w;
  const float x1 = x + 0.5f * w;
  return (pt_pulsetrain_integral(x1, duty) - pt_pulsetrain_integral(x0, duty)) / w;
}

// Smooth step with an antialiasing width added to the shader's own softness.
float pt_aa_smoothstep(float e0, float e1, float x, float w) {
  const float half_w = 0.5f * w;
  return smoothstep(e0 - half_w, e1 + half_w, x);
}

// Coverage of a shape from its signed distance d (negative inside) at footprint w: 1 inside.
float pt_coverage(float d, float w) { return clamp(0.5f - d / fmax(w, 1e-6f), 0.0f, 1.0f); }

// Brick/tile cell addressing. p in units where one row is 1 high and a cell is `ratio` wide;
// rows are shifted by `shift` (fraction of a cell) per row. Returns the cell index in .xy (as
// floats) and the position within the cell in .zw (x in [0, ratio), y in [0, 1)).
float4 pt_brick_cell(float2 p, float ratio, float shift) {
  const float row = floor(p.y);
  const float x = p.x + row * shift * ratio;
  const float col = floor(x / ratio);
  return (float4)(col, row, x - col * ratio, p.y - row);
}
