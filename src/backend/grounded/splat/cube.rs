//! The splat kernels for burn's cubecl backend (wgpu, CUDA): forward is one unit per Gaussian
//! and window voxel, adding its weighted features into the logits with atomic float adds;
//! backward is one unit per Gaussian, walking its window and writing its own gradient row (no
//! atomics). A device without atomic float add runs the host code instead (`op::host_forward`).
//! On a device the order of the atomic adds is not fixed, so logits may differ from the CPU's in
//! the last bits; the CPU path is the byte-reproducible one.

use super::layout::{self, COLS, SplatShape};
use super::op::{SplatOps, host_backward, host_forward};
use crate::backend::layout::{N_LABELS, NZ};
use burn::backend::DType;
use burn::backend::tensor::FloatTensor;
use burn_cubecl::CubeBackend;
use burn_cubecl::kernel::into_contiguous;
use burn_cubecl::ops::numeric::zeros_client;
use burn_cubecl::tensor::CubeTensor;
use cubecl::features::AtomicUsage;
use cubecl::ir::{ElemType, FloatKind, Type};
use cubecl::prelude::*;
use cubecl::{CubeCount, CubeDim, calculate_cube_count_elemwise};

const C: usize = COLS;
const NZC: u32 = NZ as u32;
const L: usize = N_LABELS;

#[cube(launch_unchecked)]
#[allow(clippy::too_many_arguments)]
fn splat_forward_kernel(
    g: &Tensor<f32>,
    out: &mut Tensor<Atomic<f32>>,
    n: u32,
    i0: u32,
    j0: u32,
    ni: u32,
    nj: u32,
    batch: u32,
    window: u32,
) {
    let side = 2 * window + 1;
    let cells = side * side * side;
    let pos = ABSOLUTE_POS;
    if pos >= n as usize * cells as usize {
        terminate!();
    }
    let row = pos / cells as usize;
    let cell = (pos % cells as usize) as u32;
    let base = row * C;
    let mx = g[base];
    let my = g[base + 1];
    let mz = g[base + 2];
    let finite = f32::abs(mx) < 1.0e9f32 && f32::abs(my) < 1.0e9f32 && f32::abs(mz) < 1.0e9f32;
    let b = u32::cast_from(g[base + layout::BATCH]);
    let r = window as i32;
    let vi = i32::cast_from(f32::floor(mx)) + (cell / (side * side)) as i32 - r;
    let vj = i32::cast_from(f32::floor(my)) + ((cell / side) % side) as i32 - r;
    let vk = i32::cast_from(f32::floor(mz)) + (cell % side) as i32 - r;
    let li = vi - i0 as i32;
    let lj = vj - j0 as i32;
    let inside = li >= 0 && lj >= 0 && vk >= 0 && li < ni as i32 && lj < nj as i32 && vk < NZC as i32;
    if finite && b < batch && inside {
        let dx = f32::cast_from(vi) + 0.5f32 - mx;
        let dy = f32::cast_from(vj) + 0.5f32 - my;
        let dz = f32::cast_from(vk) + 0.5f32 - mz;
        let mut q = 0.0f32;
        #[unroll]
        for j in 0..3usize {
            let u = dx * g[base + layout::ROT + j]
                + dy * g[base + layout::ROT + 3 + j]
                + dz * g[base + layout::ROT + 6 + j];
            let t = u / g[base + layout::SCALE + j];
            q += t * t;
        }
        let w = g[base + layout::OPACITY] * f32::exp(-0.5f32 * q);
        let voxel = b as usize * (ni * nj * NZC) as usize + ((li as u32 * nj + lj as u32) * NZC + vk as u32) as usize;
        #[unroll]
        for l in 0..L {
            out[voxel * L + l].fetch_add(w * g[base + layout::FEAT + l]);
        }
    }
}

#[cube(launch_unchecked)]
#[allow(clippy::too_many_arguments)]
fn splat_backward_kernel(
    g: &Tensor<f32>,
    grad: &Tensor<f32>,
    out: &mut Tensor<f32>,
    n: u32,
    i0: u32,
    j0: u32,
    ni: u32,
    nj: u32,
    batch: u32,
    window: u32,
) {
    let row = ABSOLUTE_POS;
    if row >= n as usize {
        terminate!();
    }
    let base = row * C;
    let mx = g[base];
    let my = g[base + 1];
    let mz = g[base + 2];
    let finite = f32::abs(mx) < 1.0e9f32 && f32::abs(my) < 1.0e9f32 && f32::abs(mz) < 1.0e9f32;
    let b = u32::cast_from(g[base + layout::BATCH]);
    if finite && b < batch {
        let a = g[base + layout::OPACITY];
        let mut acc = Array::<f32>::new(C);
        #[unroll]
        for c in 0..C {
            acc[c] = 0.0f32;
        }
        let r = window as i32;
        let ci = i32::cast_from(f32::floor(mx));
        let cj = i32::cast_from(f32::floor(my));
        let ck = i32::cast_from(f32::floor(mz));
        let grid = b as usize * (ni * nj * NZC) as usize;
        for di in 0..2 * window + 1 {
            let vi = ci + di as i32 - r;
            let li = vi - i0 as i32;
            for dj in 0..2 * window + 1 {
                let vj = cj + dj as i32 - r;
                let lj = vj - j0 as i32;
                for dk in 0..2 * window + 1 {
                    let vk = ck + dk as i32 - r;
                    let inside = li >= 0 && lj >= 0 && vk >= 0 && li < ni as i32 && lj < nj as i32 && vk < NZC as i32;
                    if inside {
                        let voxel = grid + ((li as u32 * nj + lj as u32) * NZC + vk as u32) as usize;
                        let d0 = f32::cast_from(vi) + 0.5f32 - mx;
                        let d1 = f32::cast_from(vj) + 0.5f32 - my;
                        let d2 = f32::cast_from(vk) + 0.5f32 - mz;
                        let mut u = Array::<f32>::new(3usize);
                        let mut q = 0.0f32;
                        #[unroll]
                        for j in 0..3usize {
                            let uj = d0 * g[base + layout::ROT + j]
                                + d1 * g[base + layout::ROT + 3 + j]
                                + d2 * g[base + layout::ROT + 6 + j];
                            u[j] = uj;
                            let t = uj / g[base + layout::SCALE + j];
                            q += t * t;
                        }
                        let e = f32::exp(-0.5f32 * q);
                        let w = a * e;
                        let mut gw = 0.0f32;
                        #[unroll]
                        for l in 0..L {
                            let gv = grad[voxel * L + l];
                            acc[layout::FEAT + l] += w * gv;
                            gw += g[base + layout::FEAT + l] * gv;
                        }
                        acc[layout::OPACITY] += gw * e;
                        let gq = -0.5f32 * gw * w;
                        let mut gu = Array::<f32>::new(3usize);
                        #[unroll]
                        for j in 0..3usize {
                            let inv = 1.0f32 / g[base + layout::SCALE + j];
                            gu[j] = gq * 2.0f32 * u[j] * inv * inv;
                            acc[layout::SCALE + j] -= gq * 2.0f32 * u[j] * u[j] * inv * inv * inv;
                        }
                        #[unroll]
                        for j in 0..3usize {
                            acc[layout::ROT + j] += gu[j] * d0;
                            acc[layout::ROT + 3 + j] += gu[j] * d1;
                            acc[layout::ROT + 6 + j] += gu[j] * d2;
                        }
                        #[unroll]
                        for ax in 0..3usize {
                            let gd = gu[0] * g[base + layout::ROT + 3 * ax]
                                + gu[1] * g[base + layout::ROT + 3 * ax + 1]
                                + gu[2] * g[base + layout::ROT + 3 * ax + 2];
                            acc[layout::MEAN + ax] -= gd;
                        }
                    }
                }
            }
        }
        #[unroll]
        for c in 0..C {
            out[base + c] = acc[c];
        }
    }
}

/// Whether the device adds floats atomically (CUDA and Vulkan do; WebGPU and GL do not).
fn adds_floats(t: &CubeTensor) -> bool {
    t.client.properties().atomic_type_usage(Type::atomic(ElemType::Float(FloatKind::F32))).contains(AtomicUsage::Add)
}

fn zeros(like: &CubeTensor, rows: usize, cols: usize) -> CubeTensor {
    zeros_client(like.client.clone(), like.device.clone(), [rows, cols].into(), DType::F32)
}

/// The kernels' shape arguments, in their order: i0, j0, ni, nj, batch, window.
fn scalars(s: &SplatShape) -> [u32; 6] {
    let r = &s.region;
    [r.i0, r.j0, r.ni, r.nj, s.batch, s.window].map(|v| v as u32)
}

/// A launch of one unit per element of `units`.
fn grid(t: &CubeTensor, units: usize) -> (CubeCount, CubeDim) {
    let cube_dim = CubeDim::new(&t.client, units);
    (calculate_cube_count_elemwise(&t.client, units, cube_dim), cube_dim)
}

impl SplatOps for CubeBackend {
    fn splat_forward(g: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self> {
        if !adds_floats(&g) || g.dtype != DType::F32 {
            return host_forward::<Self>(g, s);
        }
        let g = into_contiguous(g);
        let n = g.meta.shape()[0];
        let out = zeros(&g, s.batch * s.region.voxels(), N_LABELS);
        let side = 2 * s.window + 1;
        let units = n * side * side * side;
        if units == 0 {
            return out;
        }
        let (count, dim) = grid(&g, units);
        let [i0, j0, ni, nj, batch, window] = scalars(&s);
        let client = g.client.clone();
        unsafe {
            splat_forward_kernel::launch_unchecked(
                &client,
                count,
                dim,
                g.into_tensor_arg(),
                out.clone().into_tensor_arg(),
                n as u32,
                i0,
                j0,
                ni,
                nj,
                batch,
                window,
            );
        }
        out
    }

    fn splat_backward(g: FloatTensor<Self>, grad: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self> {
        if !adds_floats(&g) || g.dtype != DType::F32 || grad.dtype != DType::F32 {
            return host_backward::<Self>(g, grad, s);
        }
        let g = into_contiguous(g);
        let grad = into_contiguous(grad);
        let n = g.meta.shape()[0];
        let out = zeros(&g, n, COLS);
        if n == 0 {
            return out;
        }
        let (count, dim) = grid(&g, n);
        let [i0, j0, ni, nj, batch, window] = scalars(&s);
        let client = g.client.clone();
        unsafe {
            splat_backward_kernel::launch_unchecked(
                &client,
                count,
                dim,
                g.into_tensor_arg(),
                grad.into_tensor_arg(),
                out.clone().into_tensor_arg(),
                n as u32,
                i0,
                j0,
                ni,
                nj,
                batch,
                window,
            );
        }
        out
    }
}
