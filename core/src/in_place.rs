//! Building large structs in their final place. The firmware's controller, protocol,
//! machine, pipeline and planner (several KB together) are written field by field into
//! their static cells by each type's `init_in`, so that no whole value is built on
//! init's stack and then copied. `new` for the same types goes through [`build`], so
//! each type lists its initial values once, in `init_in`.

use core::mem::MaybeUninit;

/// A value made by an `init_in`-style constructor: `init` fills the slot and returns it
/// as initialised.
///
/// Panics if `init` returns a reference to anything but the slot (a constructor bug).
/// Otherwise the slot is initialised: a `&mut T` into the slot can only come from an
/// `unsafe` `assume_init_mut` in the constructor, which vouches for every field.
#[allow(unsafe_code)]
pub fn build<T>(init: impl for<'a> FnOnce(&'a mut MaybeUninit<T>) -> &'a mut T) -> T {
    let mut slot = MaybeUninit::uninit();
    let at: *const T = slot.as_ptr();
    let made: *const T = init(&mut slot);
    assert!(core::ptr::eq(made, at), "init_in returned another value");
    // SAFETY: `init` returned the slot itself as an initialised `&mut T` (see above).
    unsafe { slot.assume_init() }
}
