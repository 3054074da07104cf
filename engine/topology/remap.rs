//! The one remap of per-vertex arrays after a topology change.
//!
//! `old_of_new[row]` is, for each row of the new arrays, the row it comes from in the old
//! arrays, or [`NEW_ROW`] for a brand-new row. Every per-vertex array (parameters, optimizer
//! moments, gradient statistics, keypoint bindings, colours) goes through [`remap_rows`] or
//! [`remap_strided`] with the same `old_of_new`, so they cannot drift apart.

/// Marks a row with no old counterpart.
pub const NEW_ROW: u32 = u32::MAX;

/// New per-vertex array with `stride` values per row: kept rows copied from `old`, new rows
/// written by `fill(new_row, row_values)` (which receives the row zeroed to `T::default()`).
/// Panics if an index in `old_of_new` is past the old rows (it comes from this module, not from
/// user data).
pub fn remap_strided<T: Copy + Default>(
    old: &[T],
    stride: usize,
    old_of_new: &[u32],
    mut fill: impl FnMut(usize, &mut [T]),
) -> Vec<T> {
    let mut out = vec![T::default(); old_of_new.len() * stride];
    for (row, (&from, dst)) in
        old_of_new.iter().zip(out.chunks_exact_mut(stride.max(1))).enumerate()
    {
        if from == NEW_ROW {
            fill(row, dst);
        } else {
            let src = from as usize * stride;
            dst.copy_from_slice(&old[src..src + stride]);
        }
    }
    out
}

/// [`remap_strided`] with one `T` per row; new rows get `fill(new_row)`.
pub fn remap_rows<T: Copy + Default>(
    old: &[T],
    old_of_new: &[u32],
    mut fill: impl FnMut(usize) -> T,
) -> Vec<T> {
    remap_strided(old, 1, old_of_new, |row, dst| dst[0] = fill(row))
}

/// Composes two remaps applied one after the other (`first`, then `second`).
pub fn compose(first: &[u32], second: &[u32]) -> Vec<u32> {
    second.iter().map(|&r| if r == NEW_ROW { NEW_ROW } else { first[r as usize] }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kept_rows_keep_their_ids_and_new_rows_are_filled() {
        let ids: Vec<u32> = (100..105).collect();
        let old_of_new = [4, NEW_ROW, 0, 2, NEW_ROW];
        let out = remap_rows(&ids, &old_of_new, |row| 1000 + row as u32);
        assert_eq!(out, vec![104, 1001, 100, 102, 1004]);
        let pairs: Vec<f32> = (0..10).map(|i| i as f32).collect();
        let out = remap_strided(&pairs, 2, &[3, NEW_ROW], |_, dst| dst.fill(-1.0));
        assert_eq!(out, vec![6.0, 7.0, -1.0, -1.0]);
    }

    #[test]
    fn composition_follows_rows_through_both_steps() {
        let first = [2, 0, NEW_ROW];
        let second = [2, 1, NEW_ROW, 0];
        assert_eq!(compose(&first, &second), vec![NEW_ROW, 0, NEW_ROW, 2]);
    }
}
