//! E09xx: the learned (grounded) occupancy backend and `rocc train`.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0901",
        title: "grounded weights missing",
        explanation: "`--backend grounded` (or `rocc train generator --init`) names a weights file that does not\n\
exist, or `--backend grounded` was given without `--weights`. Train weights first:\n
    rocc compile scenarios/ -o corpus --stage occ --no-previews
    rocc train autoencoder --data corpus --config configs/cpu-small.ron --out model
    rocc train generator   --data corpus --config configs/cpu-small.ron --out model
    rocc compile FILE -o out --backend grounded --weights model/generator.bpk\n\n\
`rocc train` writes `OUT/<stage>.bpk` and the config beside it as `OUT/<stage>.ron`. `rocc edit`\n\
on a clip of the learned backend reruns it with the weights its manifest records; if they moved,\n\
pass the same file with `--weights`.",
    },
    Code {
        code: "E0902",
        title: "grounded config unreadable or invalid",
        explanation: "The model's shapes come from a RON config (`configs/paper.ron`, `configs/cpu-small.ron`).\n\
By default rocc reads the `.ron` next to the weights file (`model/generator.bpk` ->\n\
`model/generator.ron`, which `rocc train` writes); `--grounded-config FILE` names another. The\n\
file could not be read, is not valid RON for `GroundedConfig`, or breaks a rule: `max_foreground`\n\
<= `latents`, decoder `width` a multiple of `heads`, `window` 1..=6 voxels, `min_scale` below\n\
`window / 3`, BEV `strides` of 1 or 2 matching `channels`, `crop` 0 or 16..=400, learning rates\n\
positive with `lr_min <= lr`. The message lists every broken rule.

    ( batch: 0, lr: 1e-3, ... )   // error: `batch` must be at least 1",
    },
    Code {
        code: "E0903",
        title: "weights do not fit the model",
        explanation: "The weights file was read, but its tensors do not match the model the config describes:\n\
a tensor is missing, has another shape, or is not part of the model. Usual causes: the config is\n\
not the one the weights were trained with (use the `.ron` `rocc train` wrote beside them), or the\n\
file is an autoencoder checkpoint where a generator is needed (`--backend grounded` needs\n\
`generator.bpk`). Safetensors files must name tensors by burn's module paths\n\
(`decoder.transformer.layers.0.mha.query.weight`, ...); `rocc train --safetensors` writes a\n\
reference file with every name.

    rocc compile FILE -o out --backend grounded --weights paper/generator.bpk   // error if the
    // weights were trained with configs/cpu-small.ron: pass the matching config beside them",
    },
    Code {
        code: "E0904",
        title: "unknown weights format",
        explanation: "rocc reads weights as burnpack (`.bpk`, what `rocc train` writes and checkpoints) or\n\
safetensors (`.safetensors`, for weights trained elsewhere). Other extensions (`.pt`, `.ckpt`,\n\
`.mpk`) are not read; convert PyTorch state dicts to safetensors with the tensor names of\n\
burn's module paths.

    rocc compile FILE -o out --backend grounded --weights model.safetensors   // error: no tensor
    // named like a burn module path (e.g. `decoder.blocks.0.attn.query.weight`)",
    },
    Code {
        code: "E0905",
        title: "training data unusable",
        explanation: "`rocc train --data DIR` (or `--val DIR`) found no frames, or a frame could not be read.\n\
Two layouts are accepted:
  1. what `rocc compile --stage occ` writes: clips with `boxes.json`, `bev/NNNNNN.npz`,
     `occ/NNNNNN.npy`, at any depth below DIR;
  2. nuPlan-Occ / UniScene style: `DIR/bev/<token>.npz` (gt_bev_masks, gt_aux_bev),
     `DIR/occ/<token>.npy` (dense (400, 400, 32) labels 0..8) or `.npz` (sparse [i, j, k, label]
     rows), `DIR/boxes/<token>.json` ({\"gt_boxes\": [[x, y, z, l, w, h, yaw], ...],
     \"gt_names\": [...]}).\n\
The message names the file and what is wrong with it (shape, dtype, missing key). With\n\
`val_fraction` > 0 and a single clip, nothing is left to train on: add clips or pass `--val`.",
    },
    Code {
        code: "E0906",
        title: "cannot write training output",
        explanation: "`rocc train` could not create or write its output directory, a checkpoint, the weights or\n\
the history file (permissions, full disk), or could not read back a checkpoint for `--resume`.\n\
Files are written atomically, so an interrupted run leaves the previous checkpoint intact.

    rocc train autoencoder --data corpus --config configs/cpu-small.ron --out /read-only/dir",
    },
    Code {
        code: "E0907",
        title: "training diverged",
        explanation: "The loss became NaN or infinite. Lower the stage's learning rate (`train.autoencoder.lr`,\n\
`train.generator.lr`) in the config, and continue from the last good checkpoint with\n\
`--resume` (checkpoints are written every `checkpoint_every` steps and at each epoch's end).

    rocc train generator --data corpus --config configs/cpu-small.ron --out model --resume   // error: nothing to resume",
    },
    Code {
        code: "E0908",
        title: "bad backend or device option",
        explanation: "An option of the learned backend does not apply: `--weights` or `--grounded-config` given\n\
with `--backend procedural`, or `--device wgpu|cuda` on a build without that feature\n\
(`cargo build --release --features wgpu`, or `--features cuda`, which needs network access at build\n\
time; CI and the default build are CPU-only).

    rocc train autoencoder --data corpus --config configs/paper.ron --out paper --device cuda   // error in a default build",
    },
    Code {
        code: "E0910",
        title: "no usable GPU device",
        explanation: "`--device wgpu` or `--device cuda` was asked for, the build has the feature, but no device\n\
answered: no Vulkan/Metal/DX12 adapter (wgpu), no CUDA driver or GPU (cuda), or the driver\n\
refused to create a device. rocc probes the device before any work, so nothing was written.\n\
Check the driver (`vulkaninfo --summary`, `nvidia-smi`); in a container, the GPU and its\n\
Vulkan ICD must be passed through. `--device cpu` always works.

    rocc compile scene.scn -o out --backend grounded --weights model/generator.bpk --device wgpu
    // error on a machine without a GPU driver: no usable GPU device",
    },
    Code {
        code: "E0911",
        title: "out of device memory",
        explanation: "The GPU had no memory left for an allocation of the learned backend. Inference holds the\n\
full-grid logits of every frame of a forward pass (400 x 400 x 32 voxels x 9 classes, about\n\
180 MB per frame) and the splat's intermediates; training also holds the gradients. Lower\n\
`--grounded-batch` (frames per forward pass of `rocc compile`), or the config's `batch` or\n\
`train.crop` for `rocc train` (`--resume` continues from the last checkpoint), free the GPU of\n\
other work, or use another device.

    rocc compile scenarios/ -o out --backend grounded --weights paper/generator.bpk --device wgpu --grounded-batch 16
    // error on a small GPU: lower --grounded-batch",
    },
    Code {
        code: "E0912",
        title: "a buffer beyond the device's limits",
        explanation: "One tensor of the learned backend is larger than the device lets a single buffer be\n\
(wgpu's `max_buffer_size` and `max_storage_buffer_binding_size`; cubecl says `can't allocate\n\
buffer of size: N`). This depends on the size of one forward pass, not on free memory.\n\
Inference fits itself to the device's limit (the grid in strips of rows, attention in blocks\n\
of queries, fewer frames a pass); a training step's crop is not split: lower the config's\n\
`batch` or `train.crop` (train) or `--grounded-batch` (compile), or use a device with larger\n\
limits (`--device cuda`).

    rocc train generator --data nuplan/train --config configs/paper.ron --out paper --device wgpu
    // error where one splat buffer of batch 6 exceeds the adapter's limit: lower `batch` or `train.crop`",
    },
    Code {
        code: "E0913",
        title: "the device failed",
        explanation: "A GPU operation of the learned backend failed in a way rocc does not recognise (not a\n\
missing device, E0910, nor memory, E0911 and E0912); the message quotes the device's own\n\
words. Nothing of the failed clip is kept as complete: a re-run starts it again. Rerun with\n\
`--device cpu` to tell a fault of the device or its driver from one of the model or weights.

    rocc compile scene.scn -o out --backend grounded --weights model/generator.bpk --device wgpu
    // error: the device failed: `...` (the driver's message)",
    },
    Code {
        code: "E0914",
        title: "mixed precision on a device that cannot run it",
        explanation: "`--precision mixed` runs the decoder transformer's matrix products on f16\n\
operands, for GPUs with tensor cores. It is refused on the CPU (which has no fast half-precision\n\
products: it would only be slower) and on a GPU whose driver cannot compute in f16 (a first\n\
f16 product is tried before any work). Use `--precision full` (the default), which computes\n\
everything in f32 on any device.

    rocc train generator --data occ --config configs/paper.ron --out paper --device cpu --precision mixed
    // error: mixed precision is for GPUs",
    },
];
