//! One convention for the enums whose values leave the core as a byte (the firmware link, the
//! checkpoint image, the columns of the host's files): each is `#[repr(u8)]` with its codes as
//! explicit discriminants `0..N`, lists its variants in code order in a `const ALL`, turns into its
//! code with `as u8` and back with `TryFrom<u8>`, which refuses an unknown byte with
//! [`UnknownCode`]. ([`crate::Status`], whose rotation-fault variant carries the fault, keeps a
//! `code()` method instead of `as u8`, with the same `ALL` and `TryFrom<u8>`.)

/// A byte that is not the code of any variant of the enum named by `what`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnknownCode {
    /// The enum, as a reader would name it ("method", "status", ...).
    pub what: &'static str,
    /// The byte that is not one of its codes.
    pub code: u8,
}

impl core::fmt::Display for UnknownCode {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{} is not a known {} code", self.code, self.what)
    }
}

impl core::error::Error for UnknownCode {}

/// The variant of code `code` from an `ALL` listed in code order (which each enum's tests check).
pub(crate) fn from_code<T: Copy, const N: usize>(
    all: &[T; N],
    what: &'static str,
    code: u8,
) -> Result<T, UnknownCode> {
    all.get(usize::from(code))
        .copied()
        .ok_or(UnknownCode { what, code })
}

#[cfg(test)]
mod tests {
    use crate::{Field, Method, RejectReason, RotationFault, Status};

    /// `ALL` in code order is what makes [`super::from_code`] right; a new variant put anywhere but
    /// at its code's place fails here.
    #[test]
    fn every_all_is_in_code_order_and_try_from_inverts_it() {
        fn check<T: Copy + PartialEq + core::fmt::Debug + TryFrom<u8>, const N: usize>(
            all: [T; N],
            code: impl Fn(T) -> u8,
        ) {
            for (i, v) in all.iter().enumerate() {
                assert_eq!(usize::from(code(*v)), i, "{v:?}");
                assert!(T::try_from(i as u8).ok() == Some(*v), "{v:?}");
            }
            assert!(T::try_from(N as u8).is_err());
            assert!(T::try_from(u8::MAX).is_err());
        }
        check(Method::ALL, |m| m as u8);
        check(Field::ALL, |f| f as u8);
        check(RejectReason::ALL, |r| r as u8);
        check(Status::ALL, |s| s.code());
        for (i, f) in [
            RotationFault::Stopped,
            RotationFault::Reversed,
            RotationFault::RateMismatch,
        ]
        .into_iter()
        .enumerate()
        {
            assert_eq!(Status::RotationFault(f).code(), 1 + i as u8);
        }
    }

    #[test]
    fn an_unknown_code_names_the_enum_and_the_byte() {
        let e = Method::try_from(7).unwrap_err();
        assert_eq!(std::format!("{e}"), "7 is not a known method code");
    }
}
