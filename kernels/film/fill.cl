// Temporal fill of damaged pixels from motion-compensated neighbours (clpde/film/fill.py).
//
// Planes are plain (ny, nx) floats, x fastest; a frame of C channels is (C, ny, nx); the
// K neighbours' warped frames are (K, C, ny, nx), their warped grey planes, warped masks
// and validity planes (K, ny, nx). Sizes, K and C are kernel arguments.
// Launch: global (nx rounded up to the work-group, ny); items past nx return.

#define KMAX 8

// Each damaged pixel (mask m > 0) takes the value of one neighbour that sees it clean:
// its warped place is valid (V) and clean (warped mask MW below `clean`). Among those, the
// ones whose corrected grey values agree best with this frame on the clean pixels of the
// (2 rad + 1)^2 window around (mean absolute difference e_k) are kept: e_k <= 1.5 min e +
// sigma; of them the medoid of the corrected grey values is copied, every channel from the
// same neighbour, so the grain it carries comes along (a mean of neighbours would smooth
// it); ties go to the nearer frame in time. The output blends m * fill + (1 - m) * frame.
// Pixels no neighbour sees clean are left as they are and flagged in `unfilled`.
__kernel void fill_temporal(__global const float* F, __global const float* G,
                            __global const float* M, __global const float* W,
                            __global const float* Wg, __global const float* MW,
                            __global const float* V, __global const float* gain,
                            __global const float* offset, __global const float* dist,
                            const int K, const int C, const float sigma, const int rad,
                            const float clean, __global float* out,
                            __global float* unfilled, const int nx, const int ny) {
    const int x = get_global_id(0), y = get_global_id(1);
    if (x >= nx || y >= ny) return;
    const int i = y * nx + x;
    const size_t plane = (size_t)nx * (size_t)ny;
    const float m = M[i];
    for (int c = 0; c < C; ++c) out[c * plane + i] = F[c * plane + i];
    unfilled[i] = 0.0f;
    if (m <= 0.0f) return;
    int cand[KMAX];
    float e[KMAX], g[KMAX];
    int n = 0;
    float emin = INFINITY;
    for (int k = 0; k < K && k < KMAX; ++k) {
        if (V[k * plane + i] < 0.5f || MW[k * plane + i] > clean) continue;
        float s = 0.0f, cnt = 0.0f;
        for (int yy = max(y - rad, 0); yy <= min(y + rad, ny - 1); ++yy)
            for (int xx = max(x - rad, 0); xx <= min(x + rad, nx - 1); ++xx) {
                const int j = yy * nx + xx;
                if (M[j] > 0.0f || MW[k * plane + j] > clean || V[k * plane + j] < 0.5f)
                    continue;
                s += fabs(G[j] - (gain[k] * Wg[k * plane + j] + offset[k]));
                cnt += 1.0f;
            }
        e[n] = cnt > 0.0f ? s / cnt : -1.0f;  // -1: no clean context in the window
        if (cnt > 0.0f) emin = fmin(emin, e[n]);
        g[n] = gain[k] * Wg[k * plane + i] + offset[k];
        cand[n++] = k;
    }
    if (n == 0) {
        unfilled[i] = 1.0f;
        return;
    }
    int best = -1;
    float best_cost = INFINITY;
    for (int a = 0; a < n; ++a) {
        if (e[a] >= 0.0f && e[a] > 1.5f * emin + sigma) continue;
        float cost = 0.0f;
        for (int b = 0; b < n; ++b) {
            if (e[b] >= 0.0f && e[b] > 1.5f * emin + sigma) continue;
            cost += fabs(g[a] - g[b]);
        }
        // ties (two candidates always tie) go to the nearer frame, then the earlier one
        cost += 1e-6f * dist[cand[a]];
        if (cost < best_cost) { best_cost = cost; best = a; }
    }
    const int k = cand[best];
    for (int c = 0; c < C; ++c) {
        const float val = gain[k] * W[(k * C + c) * plane + i] + offset[k];
        out[c * plane + i] = m * val + (1.0f - m) * F[c * plane + i];
    }
}
