//! Building large structs in their final place. The firmware's controller, protocol,
//! machine, pipeline and planner (several KB together) are written field by field into
//! their static cells by each type's `init_in`, so that no whole value is built on
//! init's stack and then copied. `new` for the same types goes through [`build`], so
//! each type lists its initial values once, in `init_in`.
//!
//! Every `init_in` is one [`init_fields!`](crate::init_fields) call: the one place with the `unsafe` code
//! this takes, audited once here.

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

/// Writes every field of a struct into `slot` and returns it initialised:
///
/// ```ignore
/// init_fields!(slot => Machine {
///     settings = settings.clone(),           // the value, written in place
///     interpreter in |cell| Interpreter::init_in(cell), // a struct built in its own field
///     ...
/// })
/// ```
///
/// Every field must be named exactly once (a missing, repeated or unknown field fails
/// to compile), so the struct is whole when the macro vouches for it. The function
/// that uses it allows `unsafe_code` (the crate denies it elsewhere).
#[macro_export]
macro_rules! init_fields {
    ($slot:expr => $ty:ident { $($field:ident $how:tt $value:expr),* $(,)? }) => {{
        let slot: &mut ::core::mem::MaybeUninit<$ty> = $slot;
        // Names every field, with no `..`: a field left out fails to compile here.
        let _ = |whole: &$ty| {
            let $ty { $($field: _),* } = whole;
        };
        let p = slot.as_mut_ptr();
        $( $crate::init_fields!(@field p, $field $how $value); )*
        // SAFETY: `p` points to `slot`, valid for writes and properly aligned; each
        // field was written once above through a raw field pointer (no reference to the
        // uninitialised struct was made), and the pattern above names every field, so
        // the struct is initialised.
        unsafe { slot.assume_init_mut() }
    }};
    (@field $p:ident, $field:ident = $value:expr) => {{
        let value = $value;
        // SAFETY: a field of the struct `$p` points to (see the arm above), written
        // once, before anything reads it.
        unsafe { ::core::ptr::addr_of_mut!((*$p).$field).write(value) }
    }};
    (@field $p:ident, $field:ident in $init:expr) => {{
        // SAFETY: the field's place viewed as `MaybeUninit` (same layout), given to its
        // own constructor, which initialises it (checked by `build`'s contract: it
        // returns the same place as initialised).
        let cell = unsafe { &mut *::core::ptr::addr_of_mut!((*$p).$field).cast() };
        let _ = ($init)(cell);
    }};
}
