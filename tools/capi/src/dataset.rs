//! `tagsplat_dataset`: a multi-view video dataset folder, described as `tagsplat dataset info`
//! describes it.

use crate::buffers::{output_text, to_path};
use crate::context::Context;
use crate::handles::{create, get, release, Handle};
use crate::status::{call, engine, Error, Status};
use std::ffi::c_char;
use tagsplat::dataset::LoadOptions;
use tagsplat::embed::DatasetInfo;

/// What a dataset folder holds, gathered once when it is opened.
pub struct Dataset {
    /// `tagsplat dataset info --json`'s text.
    json: String,
}

impl Handle for Dataset {
    const NAME: &'static str = "tagsplat_dataset";
}

/// Opens the dataset folder `path` (own layout, Panoptic or nerfstudio) and gathers what
/// `tagsplat dataset info` says of it for `context`'s device, at `scale` (in (0, 1]; 0 means 1,
/// the files' size). `check` nonzero also decodes every image and mask (slow on large
/// captures). Stores the new handle in `*out` (NULL on failure).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_dataset_open(
    context: *const Context,
    path: *const c_char,
    scale: f64,
    check: i32,
    out: *mut *mut Dataset,
) -> Status {
    call("tagsplat_dataset_open", || unsafe {
        create("out", out, || {
            let context = get("context", context)?;
            let data = to_path("path", path)?;
            let options =
                LoadOptions { scale: (scale != 0.0).then_some(scale), ..Default::default() };
            let info = DatasetInfo::gather(&context.gpu, &data, &options, check != 0)
                .map_err(|e| engine(&e))?;
            let json = serde_json::to_string_pretty(&info)
                .map_err(|e| Error::new(Status::Internal, format!("cannot write JSON: {e}")))?;
            Ok(Dataset { json })
        })
    })
}

/// The dataset's description as the JSON `tagsplat dataset info --json` prints: a string of
/// `*needed` bytes with its NUL (`buf` NULL and `len` 0 only ask for the size).
#[no_mangle]
pub unsafe extern "C" fn tagsplat_dataset_info_json(
    dataset: *const Dataset,
    buf: *mut c_char,
    len: usize,
    needed: *mut usize,
) -> Status {
    call("tagsplat_dataset_info_json", || unsafe {
        output_text("buf", &get("dataset", dataset)?.json, (buf, len), needed)
    })
}

/// Frees `dataset` (NULL: nothing).
#[no_mangle]
pub extern "C" fn tagsplat_dataset_free(dataset: *mut Dataset) -> Status {
    call("tagsplat_dataset_free", || release("dataset", dataset))
}
