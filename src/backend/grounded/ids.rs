//! Parameter ids from the module's structure: burn draws each parameter's id at random, and the
//! ids are written into every `.bpk` (weights and checkpoints), so two identical trainings would
//! otherwise write different bytes. Each parameter's id is a hash of the model's name and the
//! path to the parameter (`decoder.head.weight`), the same in every process. A file loaded
//! later brings its own ids (burn keeps them, so a resumed optimiser finds its state).

use crate::fsio::Fnv1a;
use burn::module::{Module, ModuleMapper, Param, ParamId};
use burn::prelude::*;

/// `module` with every parameter's id drawn from `model` and the parameter's path.
pub fn stable<M: Module>(module: M, model: &str) -> M {
    module.map(&mut StableIds { model: model.to_string(), path: Vec::new() })
}

struct StableIds {
    model: String,
    path: Vec<String>,
}

impl StableIds {
    fn id(&self) -> ParamId {
        let mut h = Fnv1a::new();
        h.write(self.model.as_bytes());
        for p in &self.path {
            h.write(b".").write(p.as_bytes());
        }
        ParamId::from(h.finish())
    }

    fn with_id<T: burn::module::Parameter>(&self, param: Param<T>) -> Param<T> {
        let (_, value, mapper) = param.consume();
        Param::from_mapped_value(self.id(), value, mapper)
    }
}

impl ModuleMapper for StableIds {
    fn enter_module(&mut self, name: &str, _container_type: &str) {
        self.path.push(name.to_string());
    }

    fn exit_module(&mut self, _name: &str, _container_type: &str) {
        self.path.pop();
    }

    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        self.with_id(param)
    }

    fn map_int<const D: usize>(&mut self, param: Param<Tensor<D, Int>>) -> Param<Tensor<D, Int>> {
        self.with_id(param)
    }

    fn map_bool<const D: usize>(&mut self, param: Param<Tensor<D, Bool>>) -> Param<Tensor<D, Bool>> {
        self.with_id(param)
    }
}
