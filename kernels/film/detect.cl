// Film defect detection, per pixel (clpde/film/detect.py drives these kernels).
//
// Planes are plain (ny, nx) floats, x fastest, no ghosts; a stack of K neighbour planes is
// (K, ny, nx). Sizes and K are kernel arguments. Launch: global (nx rounded up to the
// work-group, ny); items past nx return.

#define KMAX 8

// The median of a[0 .. n), n >= 1, sorting a in place (insertion sort of <= KMAX values).
inline float median_of(float* a, const int n) {
    for (int p = 1; p < n; ++p) {
        const float t = a[p];
        int q = p - 1;
        while (q >= 0 && a[q] > t) { a[q + 1] = a[q]; --q; }
        a[q + 1] = t;
    }
    return (n & 1) ? a[n / 2] : 0.5f * (a[n / 2 - 1] + a[n / 2]);
}

// Blotch score against K motion-compensated neighbours W (already warped onto this frame),
// each with a validity plane V (1 where its warped place is inside its frame and the flow is
// trusted), a flicker gain and offset (neighbour -> this frame's brightness) and a side
// (-1 earlier, +1 later).
//
// d: how far I lies outside the range of all valid corrected neighbours (signed; 0 inside),
//    taken only where at least one neighbour on each side is valid: a blotch disagrees
//    with both sides, an occlusion or a revealed region with one side only.
// z: d in noise units, sigma + gamma * (the neighbours' range beyond 2 sigma): where the
//    neighbours disagree with each other (a motion the flow does not follow, a deforming
//    object) the scale grows and the pixel is not called a blotch on their disagreement.
// r: I minus the median of the valid corrected neighbours (0 with none).
// rp, rn: I minus the median of the valid earlier (later) neighbours, 0 with none: their
//    means over small regions find blotches too faint to stand out pixel by pixel.
// m: of the differences I - neighbour, the second least in magnitude (the least with
//    fewer than 3 neighbours; 0 with none), the temporal residual the scratch detector
//    reads: a scratch fixed on the film differs from all neighbours but one (the nearest
//    may still overlap it in a slow pan), while beside it, where one neighbour's own
//    scratch lands, the others still agree with the frame, so no ghost line appears.
__kernel void detect_blotch_score(__global const float* I, __global const float* W,
                           __global const float* V, __global const float* gain,
                           __global const float* offset, __global const int* side,
                           const int K, const float sigma, const float gamma,
                           __global float* z, __global float* r, __global float* m,
                           __global float* rp, __global float* rn,
                           const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int i = y * nx + x;
    const size_t plane = (size_t)nx * (size_t)ny;
    float vals[KMAX], pv[KMAX], nv[KMAX];
    int n = 0, before = 0, after = 0;
    float lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < K && k < KMAX; ++k) {
        if (V[k * plane + i] < 0.5f) continue;
        const float w = gain[k] * W[k * plane + i] + offset[k];
        vals[n++] = w;
        lo = fmin(lo, w);
        hi = fmax(hi, w);
        if (side[k] < 0) pv[before++] = w; else nv[after++] = w;
    }
    const float v = I[i];
    rp[i] = before ? v - median_of(pv, before) : 0.0f;
    rn[i] = after ? v - median_of(nv, after) : 0.0f;
    if (n == 0) {
        z[i] = 0.0f;
        r[i] = 0.0f;
        m[i] = 0.0f;
        return;
    }
    // the two differences of least magnitude, first-come on ties
    float least = v - vals[0], second = INFINITY;
    for (int p = 1; p < n; ++p) {
        const float dd = v - vals[p];
        if (fabs(dd) < fabs(least)) { second = least; least = dd; }
        else if (fabs(dd) < fabs(second)) second = dd;
    }
    m[i] = n >= 3 ? second : least;
    const float med = median_of(vals, n);
    r[i] = v - med;
    if (before == 0 || after == 0) {
        z[i] = 0.0f;
        return;
    }
    const float d = v > hi ? v - hi : (v < lo ? v - lo : 0.0f);
    z[i] = d / (sigma + gamma * fmax(hi - lo - 2.0f * sigma, 0.0f));
}

// Mean over the rows y - h .. y + h (clipped to the image) of each column, of values clamped
// to [-lim, lim]: a long vertical line keeps its contrast, noise and short structures shrink,
// and a strong blotch counts no more than a faint line.
__kernel void detect_column_mean(__global const float* src, __global float* dst, const int h,
                          const float lim, const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int y0 = max(y - h, 0), y1 = min(y + h, ny - 1);
    float s = 0.0f;
    for (int yy = y0; yy <= y1; ++yy) s += clamp(src[yy * nx + x], -lim, lim);
    dst[y * nx + x] = s / (float)(y1 - y0 + 1);
}

// Thin-line response across x: the value minus the mean of the two flanks at distances
// w and w + 1 on each side (clamped), so lines up to about 2w - 1 pixels wide answer and
// slow horizontal variation does not; no larger than the value itself, and zero where the
// two disagree in sign (the input is a residual, zero where nothing stands out).
__kernel void detect_line_response(__global const float* src, __global float* dst, const int w,
                            const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int row = y * nx;
    const float left = 0.5f * (src[row + max(x - w, 0)] + src[row + max(x - w - 1, 0)]);
    const float right = 0.5f * (src[row + min(x + w, nx - 1)]
                                + src[row + min(x + w + 1, nx - 1)]);
    const float v = src[row + x], d = v - 0.5f * (left + right);
    // the value itself must show the line too: between two dark lines the flanks are dark
    // and the difference alone would call the gap a bright line
    dst[row + x] = (v > 0.0f) == (d > 0.0f) ? copysign(fmin(fabs(d), fabs(v)), d) : 0.0f;
}

// The strongest same-signed value of `other` within one column of x: a scratch drifts
// slowly, so its place in the next frame is this one give or take a pixel.
inline float drift_match(__global const float* other, const int row, const int x,
                         const int nx, const float sgn) {
    float best = -INFINITY;
    for (int dx = -1; dx <= 1; ++dx) {
        const int xx = clamp(x + dx, 0, nx - 1);
        best = fmax(best, sgn * other[row + xx]);
    }
    return sgn * best;
}

// Continuity over frames: the line score z of this frame combined with the best matching
// scores of the previous and next frames (has_prev / has_next say whether they exist), as
// the larger of z alone and the normalised sum (z + z_prev + z_next) / sqrt(frames): a
// scratch present in consecutive frames adds up, noise does not.
__kernel void detect_scratch_continuity(__global const float* zprev, __global const float* z,
                                 __global const float* znext, const int has_prev,
                                 const int has_next, __global float* out,
                                 const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int row = y * nx;
    const float v = z[row + x];
    const float sgn = v >= 0.0f ? 1.0f : -1.0f;
    float s = v, n = 1.0f;
    if (has_prev) { s += drift_match(zprev, row, x, nx, sgn); n += 1.0f; }
    if (has_next) { s += drift_match(znext, row, x, nx, sgn); n += 1.0f; }
    const float joint = s / sqrt(n);
    out[row + x] = sgn * fmax(sgn * v, sgn * joint);
}

// 1 where the flow's target x + (u, v) lies inside the frame, else 0: a neighbour warped
// from outside its frame shows clamped border pixels, not the scene.
__kernel void detect_flow_inside(__global const float* u, __global const float* v,
                          __global float* out, const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int i = y * nx + x;
    const float xs = (float)x + u[i], ys = (float)y + v[i];
    out[i] = (xs >= 0.0f && xs <= (float)(nx - 1) && ys >= 0.0f && ys <= (float)(ny - 1))
             ? 1.0f : 0.0f;
}

// Mean over the (2h + 1)^2 square around each pixel (clipped to the image).
__kernel void detect_box_mean(__global const float* src, __global float* dst, const int h,
                       const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    float s = 0.0f;
    int n = 0;
    for (int yy = max(y - h, 0); yy <= min(y + h, ny - 1); ++yy)
        for (int xx = max(x - h, 0); xx <= min(x + h, nx - 1); ++xx) {
            s += src[yy * nx + xx];
            ++n;
        }
    dst[y * nx + x] = s / (float)n;
}
