// The smallest program: clpde.runtime builds it once per device to learn whether the
// device's compiler works at all (pip's PoCL 3.0 cannot compile on CPUs its LLVM 14 does
// not know, such as AMD's Zen 5), so that the default device choice can skip it.
__kernel void probe_double(__global float* a)
{
    a[get_global_id(0)] *= 2.0f;
}
