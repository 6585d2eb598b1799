//! The change detector in a checkpoint image: what it learned, not its blocks. The mean square of
//! each channel's block mean (4 `R`, rad^2), the mean product of each with the one before (4 `R`,
//! rad^2) and the blocks learned into them per pair (2 x u32).
//! The current blocks, runs and hold are not kept: a restart refills the window, and the detector
//! starts its blocks again with it.
//!
//! Checked: the mean squares within [`MAX_RESIDUAL`]^2 (a block mean is a mean of residuals), the
//! mean products within +-[`MAX_RESIDUAL`]^2; the blocks learned at most [`VARIANCE_BLOCKS`].

use super::{ChangeDetector, VARIANCE_BLOCKS};
use crate::checkpoint::wire::{Reader, Writer};
use crate::checkpoint::{
    ensure, within, within_non_negative, CheckpointError, Part, Stored, MAX_RESIDUAL, R,
};
use crate::Real;

/// What a restart keeps of the change detector (its fields of the same names).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct BlockVariance {
    mean_square_rad2: [Real; 4],
    lag_product_rad2: [Real; 4],
    learned_blocks: [u32; 2],
}

impl ChangeDetector {
    /// What a restart keeps.
    pub(crate) fn learned(&self) -> BlockVariance {
        BlockVariance {
            mean_square_rad2: self.mean_square_rad2,
            lag_product_rad2: self.lag_product_rad2,
            learned_blocks: self.learned_blocks,
        }
    }

    /// Takes over what a restart keeps; the blocks start again.
    pub(crate) fn keep_learned(&mut self, l: BlockVariance) {
        *self = ChangeDetector::NEW;
        self.mean_square_rad2 = l.mean_square_rad2;
        self.lag_product_rad2 = l.lag_product_rad2;
        self.learned_blocks = l.learned_blocks;
    }
}

impl Stored for BlockVariance {
    const LEN: usize = 8 * R + 2 * 4;
    type Context<'a> = ();

    fn write(&self, w: &mut Writer<'_>) {
        for v in self
            .mean_square_rad2
            .into_iter()
            .chain(self.lag_product_rad2)
        {
            w.real(v);
        }
        for c in self.learned_blocks {
            w.u32(c);
        }
    }

    fn read(r: &mut Reader<'_>, (): ()) -> Result<BlockVariance, CheckpointError> {
        let l = BlockVariance {
            mean_square_rad2: core::array::from_fn(|_| r.real()),
            lag_product_rad2: core::array::from_fn(|_| r.real()),
            learned_blocks: [r.u32(), r.u32()],
        };
        let bound = (MAX_RESIDUAL * MAX_RESIDUAL) as Real;
        let ok = l
            .mean_square_rad2
            .iter()
            .all(|v| within_non_negative(*v, bound))
            && l.lag_product_rad2.iter().all(|v| within(*v, bound))
            && l.learned_blocks.iter().all(|c| *c <= VARIANCE_BLOCKS);
        ensure(ok, CheckpointError::InvalidValue(Part::ChangeDetector))?;
        Ok(l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::tests::written_and_read;

    #[test]
    fn a_tampered_block_variance_is_refused_with_a_typed_error() {
        let base = BlockVariance {
            mean_square_rad2: [1e-12, 2e-12, 3e-12, 4e-12],
            lag_product_rad2: [3e-13, -1e-13, 0.0, 1e-12],
            learned_blocks: [64, 63],
        };
        let with = |edit: &dyn Fn(&mut BlockVariance)| {
            let mut t = base;
            edit(&mut t);
            written_and_read(&t, ())
        };
        assert_eq!(with(&|_| {}), Ok(base));
        let refused = Err(CheckpointError::InvalidValue(Part::ChangeDetector));
        assert_eq!(with(&|l| l.mean_square_rad2[2] = -1e-12), refused);
        assert_eq!(with(&|l| l.mean_square_rad2[0] = Real::NAN), refused);
        assert_eq!(with(&|l| l.mean_square_rad2[3] = 1e30), refused);
        assert_eq!(with(&|l| l.lag_product_rad2[1] = Real::INFINITY), refused);
        assert_eq!(
            with(&|l| l.learned_blocks[1] = VARIANCE_BLOCKS + 1),
            refused
        );
    }
}
