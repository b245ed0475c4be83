//! A grid sub-step's constraint batches in one pass over the rows: a skewed wavefront.
//!
//! Batch by batch, a sub-step reads the whole cloth a dozen times; once the cloth outgrows a core's
//! cache, each of those passes streams it from memory again. But every strip of a batch touches only
//! the rows `r − span ..= r` of its last row `r`, so the batches can follow each other down the rows a
//! few rows apart. Call the batches (and the per-row work before and after them: a cell row of the wind,
//! which reads and so *touches* the two particle rows it joins, span 1; a row's prediction, span 0;
//! a row's end of a sweep) *items* `0, 1, …`, with
//! `lag₀ = 0` and `lagᵢ₊₁ = lagᵢ + spanᵢ`. At step `t = 0, 1, …` item `i` runs on last row `t − lagᵢ`,
//! the items of one step in their order. Two strips that share a particle, of items `i < j` on last
//! rows `rᵢ` and `rⱼ`, share a row, so `rᵢ − spanᵢ ≤ rⱼ`; then `rᵢ + lagᵢ ≤ rⱼ + lagᵢ + spanᵢ ≤ rⱼ + lagⱼ`:
//! item `i` runs at an earlier step, or at the same step before `j`. Every such pair runs in the order
//! of batch by batch, so every projection reads the same positions and gives the same bits; only
//! `depth + 1` rows (`depth` = the last item's lag plus its span) are in flight at a time.
//!
//! With threads the rows are cut into `parts` parts at rows `R_p = p·rows/parts`. First each part runs,
//! on its own, the strips that need nothing across a cut: item `i` on last rows from `R_p + lagᵢ + spanᵢ`
//! to `R_{p+1} − lagᵢ` (no margin at the cloth's own edges). A strip's predecessors (the earlier items'
//! strips that share a row with it) then lie within the margins of earlier items, by the inequality
//! above, so they ran before it in the same part. Then each cut's *seam*, the rows left over around it,
//! runs as a wavefront of its own, one thread per seam: seams touch disjoint rows when every part has at
//! least `2·depth` rows, and nothing in a part had to wait for a seam. The result is the same bits
//! whatever the number of parts (tested against an independent check of every pair of strips below, and
//! bit for bit in the solver's tests).
//!
//! Nothing here knows what a sub-step is, so the items of several sub-steps, one after another, make a
//! schedule too: each sub-step then runs its own depth of rows behind the one before, and a row is
//! read from memory once for all of them (`Simulation::pipelined_step`). The order above covers what
//! items touch through their rows; what they share otherwise (the attachments' buffers of the pins'
//! positions) is checked on the schedule where it is used (`position_based.rs`).

use std::ops::Range;

/// The schedule of a sequence of items over the rows of a grid.
#[derive(Clone, Debug)]
pub(crate) struct Wavefront {
    /// Rows of particles.
    rows: usize,
    /// Per item: rows its strips span beyond their first (0: within one row).
    spans: Vec<usize>,
    /// Per item: how many rows it runs behind the first item.
    lags: Vec<usize>,
}

impl Wavefront {
    /// The schedule of items with the given `spans` over `rows` rows.
    pub fn new(spans: Vec<usize>, rows: usize) -> Wavefront {
        let lags = spans
            .iter()
            .scan(0, |lag, span| {
                let this = *lag;
                *lag += span;
                Some(this)
            })
            .collect();
        Wavefront { rows, spans, lags }
    }

    /// Rows from the first item's row to the last row a strip of the last item touches.
    pub fn depth(&self) -> usize {
        match (self.lags.last(), self.spans.last()) {
            (Some(lag), Some(span)) => lag + span,
            _ => 0,
        }
    }

    /// Whether `parts` parts leave every part at least `2·depth` rows (and at least one), so that the
    /// seams are disjoint.
    pub fn fits(&self, parts: usize) -> bool {
        parts >= 1
            && (0..parts)
                .all(|p| self.cut(p + 1, parts) - self.cut(p, parts) >= (2 * self.depth()).max(1))
    }

    /// First row of part `p` (`p = parts`: the row after the last).
    fn cut(&self, p: usize, parts: usize) -> usize {
        p * self.rows / parts
    }

    /// Runs `work(item, last_row)` for part `part`'s own strips, in wavefront order.
    pub fn run_part(&self, part: usize, parts: usize, work: impl FnMut(usize, usize)) {
        debug_assert!(self.fits(parts) && part < parts);
        let (start, end) = (self.cut(part, parts), self.cut(part + 1, parts));
        self.sweep(
            |i| {
                let first = if part == 0 {
                    0
                } else {
                    start + self.lags[i] + self.spans[i]
                };
                let last = if part + 1 == parts {
                    self.rows
                } else {
                    end - self.lags[i]
                };
                first..last.max(first)
            },
            work,
        );
    }

    /// Runs `work(item, last_row)` for the strips around cut `seam` (`1 ≤ seam < parts`) that no part
    /// ran, in wavefront order; after every [`run_part`](Wavefront::run_part).
    pub fn run_seam(&self, seam: usize, parts: usize, work: impl FnMut(usize, usize)) {
        debug_assert!(self.fits(parts) && (1..parts).contains(&seam));
        let cut = self.cut(seam, parts);
        self.sweep(
            |i| cut - self.lags[i]..cut + self.lags[i] + self.spans[i],
            work,
        );
    }

    /// Steps `t` from the first to the last, running item `i` on row `t − lagᵢ` where that row lies in
    /// `rows_of(i)`.
    fn sweep(&self, rows_of: impl Fn(usize) -> Range<usize>, mut work: impl FnMut(usize, usize)) {
        let ranges: Vec<Range<usize>> = (0..self.lags.len()).map(rows_of).collect();
        let steps = ranges
            .iter()
            .zip(&self.lags)
            .filter(|(rows, _)| !rows.is_empty())
            .map(|(rows, lag)| rows.start + lag..rows.end + lag)
            .reduce(|a, b| a.start.min(b.start)..a.end.max(b.end));
        let Some(steps) = steps else { return };
        for t in steps {
            for (i, (rows, &lag)) in ranges.iter().zip(&self.lags).enumerate() {
                if let Some(row) = t.checked_sub(lag).filter(|row| rows.contains(row)) {
                    work(i, row);
                }
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Where an (item, last row) ran: phase 0 (parts) or 1 (seams), which part or seam, and its place in
    /// that sequence.
    pub(crate) type Slot = (u8, usize, usize);

    /// Where each (item, last row) of `plan` in `parts` parts runs (each exactly once, asserted).
    pub(crate) fn schedule(plan: &Wavefront, parts: usize) -> HashMap<(usize, usize), Slot> {
        let mut slots = HashMap::new();
        let mut record = |phase: u8, which: usize| {
            let mut order = Vec::new();
            let collect = |item, row| order.push((item, row));
            if phase == 0 {
                plan.run_part(which, parts, collect);
            } else {
                plan.run_seam(which, parts, collect);
            }
            for (place, key) in order.into_iter().enumerate() {
                assert!(
                    slots.insert(key, (phase, which, place)).is_none(),
                    "{key:?} ran twice ({parts} parts)"
                );
            }
        };
        for part in 0..parts {
            record(0, part);
        }
        for seam in 1..parts {
            record(1, seam);
        }
        slots
    }

    /// Whether `a` surely runs before `b`: earlier in the same sequence, or in a part while `b` is in a
    /// seam. Parts (and seams) run concurrently, so neither runs before the other there.
    pub(crate) fn before(a: Slot, b: Slot) -> bool {
        (a.0 == b.0 && a.1 == b.1 && a.2 < b.2) || (a.0 == 0 && b.0 == 1)
    }

    /// Every (item, row) runs exactly once, and every pair of strips of different items that share a row
    /// runs in item order, for the solver's sweeps (one and three iterations) and odd mixtures, on every
    /// number of parts that fits.
    #[test]
    fn every_pair_of_strips_sharing_a_row_runs_in_item_order() {
        let sweep = [0, 0, 2, 2, 1, 1, 1, 1, 1, 1, 0, 0, 0];
        let cases: Vec<Vec<usize>> = vec![
            sweep.to_vec(),
            sweep.repeat(2),
            sweep.repeat(3),
            vec![2, 0, 1, 2, 0, 0, 2],
            vec![1],
            vec![0],
        ];
        let mut parallel_cases = 0;
        for spans in cases {
            for rows in [3, 7, 30, 61, 100, 131, 240] {
                let plan = Wavefront::new(spans.clone(), rows);
                for parts in 1..=6 {
                    if !plan.fits(parts) {
                        continue;
                    }
                    parallel_cases += usize::from(parts > 1);
                    let slots = schedule(&plan, parts);
                    // Strips of item i exist for last rows span_i..rows.
                    for (i, &span) in spans.iter().enumerate() {
                        for row in span..rows {
                            assert!(slots.contains_key(&(i, row)), "{i}, {row} never ran");
                        }
                    }
                    for (&(i, ri), &a) in &slots {
                        if ri < spans[i] {
                            continue; // no strip of item i ends on that row
                        }
                        // The later items' strips that share a row with it: last row rj with
                        // rj − span_j ≤ ri and ri − span_i ≤ rj.
                        for (j, &span_j) in spans.iter().enumerate().skip(i + 1) {
                            for rj in (ri - spans[i]).max(span_j)..(ri + span_j + 1).min(rows) {
                                let b = slots[&(j, rj)];
                                assert!(
                                    before(a, b),
                                    "spans {spans:?}, {rows} rows, {parts} parts: \
                                     ({i}, {ri}) at {a:?} not before ({j}, {rj}) at {b:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
        assert!(parallel_cases > 10, "the parallel schedules are exercised");
    }

    /// A part needs room for both margins: too many parts do not fit.
    #[test]
    fn parts_fit_only_with_twice_the_depth_each() {
        let plan = Wavefront::new(vec![0, 2, 1, 0], 24);
        assert_eq!(plan.depth(), 3);
        assert!(plan.fits(1) && plan.fits(4));
        assert!(!plan.fits(5));
        assert!(!plan.fits(0));
    }
}
