// Dense optical flow, coarse to fine (clpde/motion/flow.py drives these kernels).
//
// Every buffer is one plain (ny, nx) plane of floats, x fastest, with no ghost cells; the
// sizes are kernel arguments, so one build serves every image size and pyramid level.
// A flow (u, v) at pixel x means frame1(x + (u, v)) ~ frame0(x), u along columns, v along
// rows; sampling clamps coordinates to the image.
//
// The model, per warp of each level: the brightness constancy linearised about the current
// flow, Ix du + Iy dv + It = 0, with a robust (Charbonnier) data weight times the
// confidence weight (zero on damaged pixels), and a quadratic smoothness term on the total
// flow u + du. It is solved by red-black successive over-relaxation in place.
//
// Launch: global (nx rounded up to the work-group, ny[, channels]); items past nx return.

inline float sample_clamped(__global const float* img, const int nx, const int ny,
                            float x, float y) {
    x = clamp(x, 0.0f, (float)(nx - 1));
    y = clamp(y, 0.0f, (float)(ny - 1));
    const int x0 = (int)floor(x), y0 = (int)floor(y);
    const int x1 = min(x0 + 1, nx - 1), y1 = min(y0 + 1, ny - 1);
    const float fx = x - (float)x0, fy = y - (float)y0;
    const float top = img[y0 * nx + x0] + fx * (img[y0 * nx + x1] - img[y0 * nx + x0]);
    const float bot = img[y1 * nx + x0] + fx * (img[y1 * nx + x1] - img[y1 * nx + x0]);
    return top + fy * (bot - top);
}

// Keys cubic convolution (a = -0.5) weights for the taps at x0 - 1 .. x0 + 2, t = x - x0.
inline float4 keys_weights(const float t) {
    return (float4)(((-0.5f * t + 1.0f) * t - 0.5f) * t,
                    (1.5f * t - 2.5f) * t * t + 1.0f,
                    ((-1.5f * t + 2.0f) * t + 0.5f) * t,
                    (0.5f * t - 0.5f) * t * t);
}

// Bicubic sample, coordinates clamped to the image and taps clamped at its borders. The
// flow's fixed point and the warped neighbours both use it: bilinear sampling blurs by a
// shift-dependent amount, which biases sub-pixel flow and smooths the grain of fills.
inline float sample_cubic(__global const float* img, const int nx, const int ny,
                          float x, float y) {
    x = clamp(x, 0.0f, (float)(nx - 1));
    y = clamp(y, 0.0f, (float)(ny - 1));
    const int x0 = (int)floor(x), y0 = (int)floor(y);
    const float4 wx = keys_weights(x - (float)x0), wy = keys_weights(y - (float)y0);
    const float wxs[4] = {wx.x, wx.y, wx.z, wx.w};
    const float wys[4] = {wy.x, wy.y, wy.z, wy.w};
    float acc = 0.0f;
    for (int a = 0; a < 4; ++a) {
        const int yy = clamp(y0 - 1 + a, 0, ny - 1);
        float row = 0.0f;
        for (int b = 0; b < 4; ++b)
            row += wxs[b] * img[yy * nx + clamp(x0 - 1 + b, 0, nx - 1)];
        acc += wys[a] * row;
    }
    return acc;
}

// Halve a level: a separable [1 3 3 1]/8 binomial around (2x + 0.5, 2y + 0.5), weighted by
// the confidence w so that damaged pixels do not leak into the coarse image; where a whole
// footprint is damaged the plain average stands in. wdst is the footprint's mean weight.
__kernel void flow_down(__global const float* src, __global const float* wsrc,
                        __global float* dst, __global float* wdst,
                        const int nx, const int ny, const int nx2, const int ny2) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx2 || y >= ny2) return;
    const float k[4] = {1.0f, 3.0f, 3.0f, 1.0f};
    float sw = 0.0f, swv = 0.0f, sk = 0.0f, skv = 0.0f;
    for (int a = 0; a < 4; ++a) {
        const int yy = clamp(2 * y - 1 + a, 0, ny - 1);
        for (int b = 0; b < 4; ++b) {
            const int xx = clamp(2 * x - 1 + b, 0, nx - 1);
            const float kk = k[a] * k[b];
            const float val = src[yy * nx + xx], wt = wsrc[yy * nx + xx];
            sk += kk;
            skv += kk * val;
            sw += kk * wt;
            swv += kk * wt * val;
        }
    }
    dst[y * nx2 + x] = sw > 1e-6f * sk ? swv / sw : skv / sk;
    wdst[y * nx2 + x] = sw / sk;
}

// A coarse flow (nx2, ny2) onto the finer grid (nx, ny): sampled at the fine pixel's centre
// and scaled by the size ratio along each axis.
__kernel void flow_up(__global const float* u2, __global const float* v2,
                      __global float* u, __global float* v,
                      const int nx2, const int ny2, const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const float rx = (float)nx / (float)nx2, ry = (float)ny / (float)ny2;
    const float xc = ((float)x + 0.5f) / rx - 0.5f, yc = ((float)y + 0.5f) / ry - 0.5f;
    u[y * nx + x] = rx * sample_clamped(u2, nx2, ny2, xc, yc);
    v[y * nx + x] = ry * sample_clamped(v2, nx2, ny2, xc, yc);
}

// Linearise about the flow (u, v): It = I1(x + flow) - I0(x), I1 sampled bicubically; the gradient is the mean of
// I0's and of I1's at the warped place (central differences); the data weight is w0 at x
// times w1 at the warped place (each the minimum over its stencil), and zero where the
// warped place falls outside frame1.
__kernel void flow_linearise(__global const float* I0, __global const float* I1,
                             __global const float* w0, __global const float* w1,
                             __global const float* u, __global const float* v,
                             __global float* Ix, __global float* Iy, __global float* It,
                             __global float* wd, const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int i = y * nx + x;
    const float xs = (float)x + u[i], ys = (float)y + v[i];
    const float xm = (float)max(x - 1, 0), xp = (float)min(x + 1, nx - 1);
    const float ym = (float)max(y - 1, 0), yp = (float)min(y + 1, ny - 1);
    const float g0x = (sample_clamped(I0, nx, ny, xp, (float)y)
                       - sample_clamped(I0, nx, ny, xm, (float)y)) / max(xp - xm, 1.0f);
    const float g0y = (sample_clamped(I0, nx, ny, (float)x, yp)
                       - sample_clamped(I0, nx, ny, (float)x, ym)) / max(yp - ym, 1.0f);
    const float g1x = 0.5f * (sample_cubic(I1, nx, ny, xs + 1.0f, ys)
                              - sample_cubic(I1, nx, ny, xs - 1.0f, ys));
    const float g1y = 0.5f * (sample_cubic(I1, nx, ny, xs, ys + 1.0f)
                              - sample_cubic(I1, nx, ny, xs, ys - 1.0f));
    Ix[i] = 0.5f * (g0x + g1x);
    Iy[i] = 0.5f * (g0y + g1y);
    It[i] = sample_cubic(I1, nx, ny, xs, ys) - I0[i];
    const int inside = xs >= 0.0f && xs <= (float)(nx - 1) && ys >= 0.0f
                       && ys <= (float)(ny - 1);
    // The weights' minimum over each difference stencil: a clean pixel next to a blotch
    // would otherwise bring the blotch's edge in through its gradient.
    const float c0 = fmin(fmin(w0[i], fmin(w0[y * nx + (int)xm], w0[y * nx + (int)xp])),
                          fmin(w0[(int)ym * nx + x], w0[(int)yp * nx + x]));
    const float c1 = fmin(fmin(sample_clamped(w1, nx, ny, xs, ys),
                               fmin(sample_clamped(w1, nx, ny, xs - 1.0f, ys),
                                    sample_clamped(w1, nx, ny, xs + 1.0f, ys))),
                          fmin(sample_clamped(w1, nx, ny, xs, ys - 1.0f),
                               sample_clamped(w1, nx, ny, xs, ys + 1.0f)));
    wd[i] = inside ? c0 * c1 : 0.0f;
}

// One half sweep of red-black SOR for the increment (du, dv) on pixels with
// (x + y) % 2 == parity. The smoothness target is the neighbours' mean total flow minus this
// pixel's u (Neumann: only neighbours inside count); the data weight is wd times the
// Charbonnier factor eps / sqrt(r^2 + eps^2) of the current residual r, lagged per sweep.
__kernel void flow_sor(__global const float* Ix, __global const float* Iy,
                       __global const float* It, __global const float* wd,
                       __global const float* u, __global const float* v,
                       __global float* du, __global float* dv,
                       const float alpha2, const float eps, const float omega,
                       const int parity, const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny || ((x + y) & 1) != parity) return;
    const int i = y * nx + x;
    float su = 0.0f, sv = 0.0f, n = 0.0f;
    if (x > 0) { su += u[i - 1] + du[i - 1]; sv += v[i - 1] + dv[i - 1]; n += 1.0f; }
    if (x < nx - 1) { su += u[i + 1] + du[i + 1]; sv += v[i + 1] + dv[i + 1]; n += 1.0f; }
    if (y > 0) { su += u[i - nx] + du[i - nx]; sv += v[i - nx] + dv[i - nx]; n += 1.0f; }
    if (y < ny - 1) { su += u[i + nx] + du[i + nx]; sv += v[i + nx] + dv[i + nx]; n += 1.0f; }
    const float bu = (n > 0.0f ? su / n : u[i] + du[i]) - u[i];
    const float bv = (n > 0.0f ? sv / n : v[i] + dv[i]) - v[i];
    const float gx = Ix[i], gy = Iy[i], gt = It[i];
    const float r = gx * du[i] + gy * dv[i] + gt;
    const float w = wd[i] * eps / sqrt(r * r + eps * eps);
    const float q = w * (gx * bu + gy * bv + gt) / (alpha2 + w * (gx * gx + gy * gy));
    du[i] += omega * (bu - gx * q - du[i]);
    dv[i] += omega * (bv - gy * q - dv[i]);
}

// u += du, v += dv, then the increments back to zero for the next warp.
__kernel void flow_accept(__global float* u, __global float* v,
                          __global float* du, __global float* dv,
                          const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int i = y * nx + x;
    u[i] += du[i];
    v[i] += dv[i];
    du[i] = 0.0f;
    dv[i] = 0.0f;
}

// 3x3 median of one flow component (clamped borders): removes the isolated wrong vectors
// that warping leaves, as in the classical practice between warps.
__kernel void flow_median3(__global const float* src, __global float* dst,
                           const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    float a[9];
    int n = 0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
            a[n++] = src[clamp(y + dy, 0, ny - 1) * nx + clamp(x + dx, 0, nx - 1)];
    for (int p = 1; p < 9; ++p) {  // insertion sort of nine values
        const float t = a[p];
        int q = p - 1;
        while (q >= 0 && a[q] > t) { a[q + 1] = a[q]; --q; }
        a[q + 1] = t;
    }
    dst[y * nx + x] = a[4];
}

// Backward warp of every channel: dst[c](x) = src[c](x + flow(x)), bicubic, clamped.
// Global (nx rounded up, ny, channels).
__kernel void flow_warp_image(__global const float* src, __global const float* u,
                         __global const float* v, __global float* dst,
                         const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1), c = get_global_id(2);
    if (x >= nx || y >= ny) return;
    const int i = y * nx + x;
    const size_t plane = (size_t)nx * (size_t)ny;
    dst[c * plane + i] = sample_cubic(src + c * plane, nx, ny, (float)x + u[i],
                                        (float)y + v[i]);
}
