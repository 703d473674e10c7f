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
  const float n = pt_floor(x);
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
  const float row = pt_floor(p.y);
  const float x = p.x + row * shift * ratio;
  const float col = pt_floor(x / ratio);
  return (float4)(col, row, x - col * ratio, p.y - row);
}

// Soft periodic pulse train: a unit-period pulse of the given duty whose edges are ramps of width
// `softness` (period units), box-filtered over w. A box filtered by a box is a trapezoid, so the
// softness and the antialiasing compose exactly; once softness + w exceeds a period the result
// is the duty cycle (the exact average).
float pt_soft_pulsetrain(float duty, float x, float w, float softness) {
  return pt_filtered_pulsetrain(duty, x, fmax(w, 1e-6f) + fmax(softness, 0.0f));
}

// Filtered threshold of a smooth field v (noise) at t with softness s (v units) and footprint w
// (v units: the field's change across one pixel).
float pt_aa_threshold(float v, float t, float s, float w) {
  const float h = 0.5f * fmax(s, 0.0f) + 0.5f * fmax(w, 1e-6f);
  return smoothstep(t - h, t + h, v);
}

// Fades a detail term towards its mean once its period spans fewer than ~2 pixels:
// returns a weight in [0, 1]; `period_pixels` = period / footprint.
float pt_detail_weight(float period_pixels) { return clamp(period_pixels * 0.5f - 1.0f, 0.0f, 1.0f); }

// Bias and gain (Perlin): bias(t, b) moves the midpoint to b; gain(t, g) adds contrast (g > 0.5).
float pt_bias(float t, float b) { return pt_powr(clamp(t, 0.0f, 1.0f), native_log2(clamp(b, 1e-4f, 0.9999f)) * -1.0f); }
float pt_gain(float t, float g) {
  t = clamp(t, 0.0f, 1.0f);
  return t < 0.5f ? 0.5f * pt_bias(2.0f * t, 1.0f - g) : 1.0f - 0.5f * pt_bias(2.0f - 2.0f * t, 1.0f - g);
}

// Rotates p by `angle` radians (counter-clockwise in x right / y up; clockwise on screen, y down).
float2 pt_rotate(float2 p, float angle) {
  const float c = native_cos(angle), s = native_sin(angle);
  return (float2)(c * p.x - s * p.y, s * p.x + c * p.y);
}

// Brick bonds on top of pt_brick_cell. Returns cell index .xy and in-cell position .zw, plus the
// cell's length in *len (row height 1). bond: 0 running (half shift), 1 stack, 2 English (stretcher
// rows alternate with header rows of half-length bricks), 3 Flemish (stretcher + header in every row).
float4 pt_bond_cell(float2 p, float ratio, int bond, float* len) {
  const float row = pt_floor(p.y);
  const int odd = ((int)row) & 1;
  if (bond == 1) {
    *len = ratio;
    return pt_brick_cell(p, ratio, 0.0f);
  }
  if (bond == 2) {
    if (odd) {
      *len = 0.5f * ratio;
      return pt_brick_cell(p + (float2)(0.25f * ratio, 0.0f), 0.5f * ratio, 0.0f);
    }
    *len = ratio;
    return pt_brick_cell(p, ratio, 0.0f);
  }
  if (bond == 3) {
    const float period = 1.5f * ratio;
    const float x = p.x + (odd ? 0.75f * ratio : 0.0f);
    const float k = pt_floor(x / period);
    const float u = x - k * period;
    const int second = u >= ratio;
    *len = second ? 0.5f * ratio : ratio;
    return (float4)(2.0f * k + (float)second, row, second ? u - ratio : u, p.y - row);
  }
  *len = ratio;
  return pt_brick_cell(p, ratio, 0.5f);
}

// Coverage of a line (stroke) of half width hw at distance d from its centre line, footprint w.
// Lines thinner than a pixel are drawn one pixel wide with their area kept (dimmer, not broken).
float pt_line_coverage(float d, float hw, float w) {
  const float eff = fmax(hw, 0.5f * w);
  return pt_coverage(d - eff, w) * (hw / eff);
}
