//! The numpy buffer a volume reads in place: a C-contiguous array of a scalar type Volux
//! holds (`uint8`, `uint16`, `int16`, `float32`, native byte order) is wrapped without a
//! copy, so a 2 GB CT costs no second 2 GB, and a change the user makes in place
//! (`array[...] = v`, then `volume.modified()`) is what the next frame draws.
//!
//! This is the crate's one `unsafe` block, the boundary every zero-copy binding has (numpy
//! hands a pointer, Rust needs a slice); it is not SIMD, and lives here, alone, for that
//! reason. The slice is sound because the array object is kept alive by [`NumpyBytes`] (a
//! numpy array never moves or frees its data while referenced), the bytes are read only,
//! and the length is numpy's own `nbytes` of a C-contiguous array.
use std::sync::Arc;

use numpy::{Element, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use volux_core::samples::SharedBytes;
use volux_core::{Buffer, Samples};

/// The bytes of a C-contiguous numpy array, and the array that owns them.
pub struct NumpyBytes {
    /// The array: holding it keeps the bytes alive.
    array: Py<PyUntypedArray>,
    /// The first byte's address.
    address: usize,
    /// The byte count.
    len: usize,
}

impl std::fmt::Debug for NumpyBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NumpyBytes")
            .field("address", &self.address)
            .field("len", &self.len)
            .finish()
    }
}

impl SharedBytes for NumpyBytes {
    fn bytes(&self) -> &[u8] {
        if self.len == 0 {
            return &[];
        }
        #[allow(unsafe_code)]
        // SAFETY: `address` and `len` are the data pointer and `nbytes` of a C-contiguous
        // numpy array (checked in `share`), whose data stays allocated and in place while
        // `self.array` holds a reference to it; the bytes are only read. A concurrent write
        // from Python while a frame is drawn changes values, not memory safety of the
        // plain-old-data read (documented on `Volume.modified`).
        unsafe {
            std::slice::from_raw_parts(self.address as *const u8, self.len)
        }
    }
}

impl NumpyBytes {
    /// The array object.
    pub fn array<'py>(&self, py: Python<'py>) -> Bound<'py, PyUntypedArray> {
        self.array.bind(py).clone()
    }
}

/// The samples of `array` read in place when it is C-contiguous with a scalar type Volux
/// holds in native byte order; `None` otherwise (the caller converts it).
pub fn share(array: &Bound<'_, PyUntypedArray>) -> PyResult<Option<(Samples, Arc<NumpyBytes>)>> {
    if !array.is_c_contiguous() {
        return Ok(None);
    }
    if let Some(shared) = share_as::<u8>(array, Samples::U8)? {
        return Ok(Some(shared));
    }
    if let Some(shared) = share_as::<u16>(array, Samples::U16)? {
        return Ok(Some(shared));
    }
    if let Some(shared) = share_as::<i16>(array, Samples::I16)? {
        return Ok(Some(shared));
    }
    share_as::<f32>(array, Samples::F32)
}

/// The samples of `array` read in place as `T` (wrapped by `wrap`), when its dtype is `T`.
fn share_as<T: Element + volux_core::samples::Scalar>(
    array: &Bound<'_, PyUntypedArray>,
    wrap: fn(Buffer<T>) -> Samples,
) -> PyResult<Option<(Samples, Arc<NumpyBytes>)>> {
    let Ok(typed) = array.cast::<PyArrayDyn<T>>() else {
        return Ok(None);
    };
    let owner = Arc::new(NumpyBytes {
        array: array.clone().unbind(),
        address: typed.data() as usize,
        len: typed.len() * std::mem::size_of::<T>(),
    });
    let bytes: Arc<dyn SharedBytes> = owner.clone();
    let buffer = Buffer::shared(bytes)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    Ok(Some((wrap(buffer), owner)))
}
