//! Conveniences for Rust hosts that want the kernel to own nothing but still need an aligned
//! buffer: an inline one with a const-generic size (for statics), and with `std` a heap one.
//! C hosts bring their own memory.

#[cfg(feature = "std")]
use crate::layout::ALIGN;

/// Inline, 64-byte aligned storage of `N` bytes, for a world in a `static` or on a large stack.
#[repr(C, align(64))]
pub struct AlignedBuffer<const N: usize> {
    bytes: [u8; N],
}

impl<const N: usize> AlignedBuffer<N> {
    /// Zeroed storage.
    pub const fn new() -> Self {
        AlignedBuffer { bytes: [0; N] }
    }

    /// The bytes, aligned to [`crate::ALIGN`].
    pub fn as_mut_bytes(&mut self) -> &mut [u8] {
        &mut self.bytes
    }
}

impl<const N: usize> Default for AlignedBuffer<N> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(feature = "std")]
mod heap {
    use super::ALIGN;
    use bytemuck::{Pod, Zeroable};
    use std::vec::Vec;

    /// A 64-byte aligned block of bytes.
    #[derive(Clone, Copy)]
    #[repr(C, align(64))]
    struct Block([u8; ALIGN]);

    // SAFETY: Block is a repr(C) byte array of exactly its alignment: no padding, any bits
    // valid.
    unsafe impl Zeroable for Block {}
    // SAFETY: as above; Copy and 'static.
    unsafe impl Pod for Block {}

    /// Heap storage of at least `bytes` bytes aligned to [`crate::ALIGN`], allocated once by the
    /// host (the kernel itself never allocates).
    pub struct HeapBuffer {
        blocks: Vec<Block>,
    }

    impl HeapBuffer {
        /// Zeroed storage of at least `bytes` bytes.
        pub fn new(bytes: usize) -> Self {
            HeapBuffer {
                blocks: std::vec![Block([0; ALIGN]); bytes.div_ceil(ALIGN)],
            }
        }

        /// The bytes, aligned to [`crate::ALIGN`].
        pub fn as_mut_bytes(&mut self) -> &mut [u8] {
            bytemuck::cast_slice_mut(&mut self.blocks)
        }

        /// The bytes, read-only.
        pub fn as_bytes(&self) -> &[u8] {
            bytemuck::cast_slice(&self.blocks)
        }
    }
}

#[cfg(feature = "std")]
pub use heap::HeapBuffer;
