//! Adam with its per-parameter update as one device kernel. burn's Adam updates each parameter
//! tensor with 13 element-wise operations (the two moments, the step, the new weights), each one
//! kernel launch on a GPU: about 1,450 of the 4,900 launches of a step with `paper`'s structure
//! (docs/learned-backend.md, "Adam in one kernel"). Here a GPU runs one kernel per
//! parameter tensor that reads the weights, the gradient and both moments once and writes the new
//! three. The CPU (`flex`) runs burn's own Adam, so CPU training keeps its bits. The state is
//! burn's `AdamState`: checkpoints are the same files either way, and one written by burn's Adam
//! resumes here. `tests/adam.rs` checks the CPU path against burn's Adam and checkpoints both ways;
//! with `--features wgpu` it checks the kernel against burn's Adam on the same device.

use burn::optim::{Adam, AdamConfig, AdamState, LearningRate, ModuleOptimizer, Optimizer};
use burn::prelude::*;

/// Adam's constants (burn's defaults: the optimiser `rocc train` has always used).
#[derive(Clone, Copy, Debug)]
struct Betas {
    beta_1: f32,
    beta_2: f32,
    epsilon: f32,
}

const BETAS: Betas = Betas { beta_1: 0.9, beta_2: 0.999, epsilon: 1e-5 };

/// The optimiser `rocc train` uses: burn's Adam on the CPU, one fused kernel per parameter on a
/// GPU.
#[derive(Clone)]
pub struct FusedAdam {
    burn: Adam,
}

impl Default for FusedAdam {
    fn default() -> Self {
        let b = BETAS;
        FusedAdam {
            burn: AdamConfig::new().with_beta_1(b.beta_1).with_beta_2(b.beta_2).with_epsilon(b.epsilon).build(),
        }
    }
}

impl FusedAdam {
    /// A whole-module optimiser, as `AdamConfig::init` gives.
    pub fn init() -> ModuleOptimizer {
        ModuleOptimizer::from(FusedAdam::default())
    }
}

impl Optimizer for FusedAdam {
    type State<const D: usize> = AdamState<D>;

    fn step<const D: usize>(
        &self,
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<Self::State<D>>,
    ) -> (Tensor<D>, Option<Self::State<D>>) {
        // With `fusion` burn's own queue fuses Adam's element-wise operations.
        #[cfg(all(any(feature = "wgpu", feature = "cuda"), not(feature = "fusion")))]
        if tensor.device() != Device::flex() {
            let f32s = |t: &Tensor<D>| t.dtype() == burn::tensor::DType::F32;
            let moments = state.as_ref().is_none_or(|s| f32s(&s.momentum.moment_1) && f32s(&s.momentum.moment_2));
            if f32s(&tensor) && f32s(&grad) && moments {
                return device::step(lr, tensor, grad, state);
            }
        }
        self.burn.step(lr, tensor, grad, state)
    }

    fn to_device<const D: usize>(state: Self::State<D>, device: &Device) -> Self::State<D> {
        Adam::to_device(state, device)
    }
}

/// The fused step on a GPU.
#[cfg(all(any(feature = "wgpu", feature = "cuda"), not(feature = "fusion")))]
mod device {
    use super::{BETAS, Betas};
    use burn::backend::tensor::FloatTensor;
    use burn::backend::{DType, Dispatch, TensorMetadata, backend_extension};
    use burn::optim::{AdamState, AdaptiveMomentumState, LearningRate};
    use burn::prelude::Tensor;
    use burn_cubecl::CubeBackend;
    use burn_cubecl::kernel::into_contiguous;
    use burn_cubecl::ops::numeric::empty_device_dtype;
    use burn_cubecl::tensor::CubeTensor;
    use cubecl::{CubeDim, calculate_cube_count_elemwise};

    /// One step's scalars, in the order and float arithmetic of burn's Adam.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct AdamFactors {
        pub beta_1: f32,
        /// `1 - beta_1`.
        pub keep_1: f32,
        pub beta_2: f32,
        /// `1 - beta_2`.
        pub keep_2: f32,
        /// `sqrt(1 - beta_2^t) / (1 - beta_1^t)`: both bias corrections.
        pub combined: f32,
        /// `epsilon * sqrt(1 - beta_2^t)`.
        pub epsilon: f32,
        pub lr: f32,
    }

    impl AdamFactors {
        fn new(b: Betas, time: usize, lr: LearningRate) -> Self {
            let t = time as i32;
            let bias_correction2_sqrt = (1.0 - b.beta_2.powi(t)).sqrt();
            AdamFactors {
                beta_1: b.beta_1,
                keep_1: 1.0 - b.beta_1,
                beta_2: b.beta_2,
                keep_2: 1.0 - b.beta_2,
                combined: bias_correction2_sqrt / (1.0 - b.beta_1.powi(t)),
                epsilon: b.epsilon * bias_correction2_sqrt,
                lr: lr as f32,
            }
        }
    }

    #[backend_extension(Cube)]
    pub trait AdamOps: burn::backend::Backend {
        /// The weights, gradient and moments (all one shape, f32) -> the new weights and moments.
        fn adam_update(
            param: FloatTensor<Self>,
            grad: FloatTensor<Self>,
            moment_1: FloatTensor<Self>,
            moment_2: FloatTensor<Self>,
            k: AdamFactors,
        ) -> (FloatTensor<Self>, FloatTensor<Self>, FloatTensor<Self>);
    }

    mod kernel {
        use cubecl::prelude::*;

        #[cube(launch_unchecked)]
        #[allow(clippy::too_many_arguments)]
        pub fn adam_kernel(
            param: &Tensor<f32>,
            grad: &Tensor<f32>,
            moment_1: &Tensor<f32>,
            moment_2: &Tensor<f32>,
            out_param: &mut Tensor<f32>,
            out_1: &mut Tensor<f32>,
            out_2: &mut Tensor<f32>,
            n: u32,
            beta_1: f32,
            keep_1: f32,
            beta_2: f32,
            keep_2: f32,
            combined: f32,
            epsilon: f32,
            lr: f32,
        ) {
            let i = ABSOLUTE_POS;
            if i >= n as usize {
                terminate!();
            }
            let g = grad[i];
            // burn's order: m1 b1 + g (1 - b1); m2 b2 + g^2 (1 - b2); m1 c / (sqrt(m2) + e); w - u lr.
            let m1 = moment_1[i] * beta_1 + g * keep_1;
            let m2 = moment_2[i] * beta_2 + g * g * keep_2;
            out_1[i] = m1;
            out_2[i] = m2;
            out_param[i] = param[i] - m1 * combined / (f32::sqrt(m2) + epsilon) * lr;
        }
    }

    impl AdamOps for CubeBackend {
        fn adam_update(
            param: CubeTensor,
            grad: CubeTensor,
            moment_1: CubeTensor,
            moment_2: CubeTensor,
            k: AdamFactors,
        ) -> (CubeTensor, CubeTensor, CubeTensor) {
            let [param, grad, moment_1, moment_2] = [param, grad, moment_1, moment_2].map(into_contiguous);
            let shape = param.shape();
            let n = shape.num_elements();
            let new = || empty_device_dtype(param.client.clone(), param.device.clone(), shape.clone(), DType::F32);
            let (out_param, out_1, out_2) = (new(), new(), new());
            if n > 0 {
                let client = param.client.clone();
                let dim = CubeDim::new(&client, n);
                let count = calculate_cube_count_elemwise(&client, n, dim);
                // Safety: every tensor holds `n` contiguous f32 and the kernel stops at `n`.
                unsafe {
                    kernel::adam_kernel::launch_unchecked(
                        &client,
                        count,
                        dim,
                        param.into_tensor_arg(),
                        grad.into_tensor_arg(),
                        moment_1.into_tensor_arg(),
                        moment_2.into_tensor_arg(),
                        out_param.clone().into_tensor_arg(),
                        out_1.clone().into_tensor_arg(),
                        out_2.clone().into_tensor_arg(),
                        n as u32,
                        k.beta_1,
                        k.keep_1,
                        k.beta_2,
                        k.keep_2,
                        k.combined,
                        k.epsilon,
                        k.lr,
                    );
                }
            }
            (out_param, out_1, out_2)
        }
    }

    pub fn step<const D: usize>(
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<AdamState<D>>,
    ) -> (Tensor<D>, Option<AdamState<D>>) {
        // The first step starts from zero moments: b * 0 + x is x, burn's first step exactly.
        let (time, m1, m2) = match state {
            Some(s) => (s.momentum.time + 1, s.momentum.moment_1, s.momentum.moment_2),
            None => (1, grad.zeros_like(), grad.zeros_like()),
        };
        let k = AdamFactors::new(BETAS, time, lr);
        let (p, m1, m2) = <Dispatch as AdamOps>::adam_update(
            tensor.into_dispatch(),
            grad.into_dispatch(),
            m1.into_dispatch(),
            m2.into_dispatch(),
            k,
        );
        let (p, m1, m2) = (Tensor::from_dispatch(p), Tensor::from_dispatch(m1), Tensor::from_dispatch(m2));
        (p, Some(AdamState::new(AdaptiveMomentumState::new(time, m1, m2))))
    }
}
