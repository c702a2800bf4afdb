// Tone mapping of the float pixels omega view sends (docs/web.md). Pure functions; the browser
// test (tests/web/test_web.py) applies the same formulas to the EXR it fetches, so keep the two
// in step.
"use strict";

const ToneMap = (() => {
  // Display value in [0, 1] of one linear channel value v.
  //   gamma:  clamp(v * 2^exposure, 0, 1) ^ (1 / gamma)
  //   filmic: the ACES fit of Narkowicz (2015) on v * 2^exposure, then ^ (1 / gamma)
  function channel(v, mode, scale, invGamma) {
    let x = v * scale;
    if (!(x > 0)) return 0;  // also NaN
    if (mode === "filmic") x = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    if (x >= 1) return 1;
    return Math.pow(x, invGamma);
  }

  // Relative error of a pixel: the mean over R, G, B of sqrt(variance) / max(|value|, 1e-3).
  function relError(rgb, vr, i) {
    let e = 0;
    for (let k = 0; k < 3; ++k) e += Math.sqrt(Math.max(vr[i + k], 0)) / Math.max(Math.abs(rgb[i + k]), 1e-3);
    return e / 3;
  }

  // False colour of a relative error: log10 from 1e-3 (blue) through 1e-2, 1e-1 to 1 (red).
  const RAMP = [[48, 18, 59], [40, 120, 230], [30, 200, 140], [240, 200, 40], [200, 30, 20]];
  function falseColour(e, out, o) {
    let t = (Math.log10(Math.max(e, 1e-6)) + 3) / 3;
    t = Math.min(Math.max(t, 0), 1) * (RAMP.length - 1);
    const i = Math.min(Math.floor(t), RAMP.length - 2), f = t - i;
    for (let k = 0; k < 3; ++k) out[o + k] = Math.round(RAMP[i][k] * (1 - f) + RAMP[i + 1][k] * f);
  }

  // Writes RGBA8 of the rect [x0, x1) x [y0, y1) of a film (rgb, vr: Float32Array, 3 per pixel,
  // width w) into image (an ImageData of the same width).
  function rect(film, image, x0, y0, x1, y1, params) {
    const scale = Math.pow(2, params.exposure), invGamma = 1 / params.gamma;
    const out = image.data, w = film.width;
    for (let y = y0; y < y1; ++y) {
      for (let x = x0; x < x1; ++x) {
        const i = 3 * (y * w + x), o = 4 * (y * w + x);
        if (params.mode === "error") {
          falseColour(relError(film.rgb, film.vr, i), out, o);
        } else {
          for (let k = 0; k < 3; ++k) out[o + k] = Math.round(255 * channel(film.rgb[i + k], params.mode, scale, invGamma));
        }
        out[o + 3] = 255;
      }
    }
  }

  return { channel, relError, falseColour, rect };
})();
