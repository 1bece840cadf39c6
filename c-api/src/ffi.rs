//! The boundary: Rust values kept in storage the C caller owns, and the
//! C pointers read and written. Every `unsafe` of the crate is here; each
//! function says what its caller must hold, and each block why it holds.
#![allow(unsafe_code)]

use core::mem::{align_of, size_of};

use crate::status::BushingStatus;

/// A kind of caller-owned storage: a `#[repr(C)]` struct of 64-bit words
/// that holds one `Value` behind a tag.
///
/// # Safety
///
/// `Self` must be a `#[repr(C)]` struct of `u64` words only (every bit
/// pattern valid, aligned to 8), and `TAG` must differ between kinds.
pub(crate) unsafe trait Storage {
    /// What the words hold.
    type Value;
    /// Written before the value by `init`; checked by every other call.
    const TAG: u64;
}

/// The layout inside the words: the tag, then the value.
#[repr(C)]
struct Tagged<V> {
    tag: u64,
    value: V,
}

/// Compile-time check that `S`'s words hold a tagged `S::Value`: a
/// storage constant too small for a target fails that target's build.
const fn fits<S: Storage>() {
    assert!(size_of::<Tagged<S::Value>>() <= size_of::<S>());
    assert!(align_of::<Tagged<S::Value>>() <= align_of::<S>());
}

/// Stores `value` in the words at `p` and tags them.
///
/// # Safety
///
/// `p` is null or points to a writable `S` that no other reference
/// aliases during the call.
pub(crate) unsafe fn put<S: Storage>(p: *mut S, value: S::Value) -> Result<(), BushingStatus> {
    const { fits::<S>() };
    if p.is_null() {
        return Err(BushingStatus::NullPointer);
    }
    let slot = p.cast::<Tagged<S::Value>>();
    // SAFETY: `p` is non-null, writable and unaliased (the caller's
    // contract); `fits` proved the words large and aligned enough for a
    // `Tagged<S::Value>`. `write` does not read or drop the old words,
    // which may be anything.
    unsafe {
        slot.write(Tagged { tag: S::TAG, value });
    }
    Ok(())
}

/// The tagged slot at `p` once its tag says `init` stored a value: the
/// null and tag checks of [`get`] and [`get_mut`].
///
/// # Safety
///
/// `p` is null or points to a readable `S` (its words written by C or by
/// [`put`]).
unsafe fn tagged<S: Storage>(p: *const S) -> Result<*const Tagged<S::Value>, BushingStatus> {
    const { fits::<S>() };
    if p.is_null() {
        return Err(BushingStatus::NullPointer);
    }
    let slot = p.cast::<Tagged<S::Value>>();
    // SAFETY: `p` is non-null and readable (the caller's contract) and
    // aligned for the tag (`fits`); the tag is a `u64`, valid for any bits.
    if unsafe { (*slot).tag } != S::TAG {
        return Err(BushingStatus::NotInitialised);
    }
    Ok(slot)
}

/// The value in the words at `p`, if `init` stored one.
///
/// # Safety
///
/// `p` is null or points to a readable, initialised `S` (its words
/// written by C or by [`put`]) that nothing writes during `'a`.
pub(crate) unsafe fn get<'a, S: Storage>(p: *const S) -> Result<&'a S::Value, BushingStatus> {
    // SAFETY: the caller's contract is `tagged`'s. Only when the tag is
    // `S::TAG` did `put` store a valid value behind it, which is then read
    // as a shared reference that nothing writes during `'a`.
    unsafe { tagged(p).map(|slot| &(*slot).value) }
}

/// The value in the words at `p`, mutably, if `init` stored one.
///
/// # Safety
///
/// As [`get`], and no other reference to the words lives during `'a`.
pub(crate) unsafe fn get_mut<'a, S: Storage>(p: *mut S) -> Result<&'a mut S::Value, BushingStatus> {
    // SAFETY: as in `get`; `p` came as a `*mut`, so writing through it is
    // allowed, and the caller guarantees the reference is the only one to
    // these words while it lives.
    unsafe { tagged(p).map(|slot| &mut (*slot.cast_mut()).value) }
}

/// The C struct at `p`, read by reference.
///
/// # Safety
///
/// `p` is null or points to a readable, initialised `T` for `'a`, and `T`
/// is a `#[repr(C)]` struct whose fields are valid for any bits (numbers,
/// not enums or `bool`).
pub(crate) unsafe fn input<'a, T>(p: *const T) -> Result<&'a T, BushingStatus> {
    // SAFETY: the caller's contract, and null is refused.
    unsafe { p.as_ref() }.ok_or(BushingStatus::NullPointer)
}

/// Writes `value` to the C struct at `p`; a null `p` is refused.
///
/// # Safety
///
/// `p` is null or points to a writable `T` that nothing else references
/// during the call.
pub(crate) unsafe fn output<T>(p: *mut T, value: T) -> Result<(), BushingStatus> {
    if p.is_null() {
        return Err(BushingStatus::NullPointer);
    }
    // SAFETY: non-null, writable and unaliased (the caller's contract);
    // `write` does not drop the old contents.
    unsafe { p.write(value) };
    Ok(())
}

/// Writes `value` to the C struct at `p` when `p` is not null (an
/// optional output such as the error detail).
///
/// # Safety
///
/// As [`output`].
pub(crate) unsafe fn optional_output<T>(p: *mut T, value: T) {
    if !p.is_null() {
        // SAFETY: the caller's contract for a non-null `p`.
        let _ = unsafe { output(p, value) };
    }
}
