//! Tensors read on the host by the CPU operations (`head`, `cross_entropy`, `conv`, the splat's
//! host code): a backend's tensor as a `Vec<f32>`, or a Flex tensor's elements in place.

use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Backend, DType};

/// Any backend's tensor, read back as f32 (synchronously: on a device, only on host paths).
pub fn host_vec<B: Backend>(t: FloatTensor<B>) -> Vec<f32> {
    let data = burn::tensor::read_sync(B::float_into_data(t)).expect("reading a tensor back from its device");
    data.convert::<f32>().try_into_vec::<f32>().unwrap_or_default()
}

/// A Flex tensor as contiguous f32 (converted or copied only where it is not).
pub fn flex_f32(t: &FlexTensor) -> FlexTensor {
    if t.dtype() == DType::F32 {
        t.to_contiguous()
    } else {
        FlexTensor::from_data(t.clone().into_data().convert::<f32>())
    }
}

/// The elements of a contiguous f32 Flex tensor (`flex_f32`), in place.
pub fn flex_slice(t: &FlexTensor) -> &[f32] {
    let start = t.layout().start_offset();
    &t.storage::<f32>()[start..start + t.layout().num_elements()]
}
