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
//! read from memory once for all of them (`Simulation::whole_step`). The order above covers what
//! items touch through their rows; what they share otherwise (the attachments' buffers of the pins'
//! positions) is checked on the schedule where it is used (`grid_step.rs`), except for opposed
//! parts (below), which the solver uses only where every attachment reads its own row's pins, so
//! that the buffers follow the rows' order.
//!
//! Two *opposed parts* keep each of two threads on its own rows without seams. Each strip goes to the
//! part that holds its first row; one part sweeps its rows downwards as above, the other upwards
//! (item `i` on first row `f` at step `b − 1 − f + lagᵢ`, `b` the row after the part's last: the same
//! order, mirrored; [`Wavefront::opposed_sweep`]), so within a part every pair of strips that share a
//! row runs in item order as in one part. Across the cut only the rows `cut .. cut + most span` are
//! touched by both, and there a strip waits until the other part has run every strip of an earlier
//! item that shares a row with it (each part's counter in [`Progress`]; which strip waits for what
//! is worked out before the pass, [`Wavefront::opposed_parts`]). The two never wait for each other
//! at once. Say part 0 sweeps down and waits at strip `x` (item `j`, last row `rₓ ≥ cut`) for part
//! 1's strip `y` (item `i < j`), while part 1, sweeping up, waits at a strip `y′` at or before `y`
//! (item `k`) for part 0's strip `x′` at or after `x` (item `a < k`, last row `rₓ′ ≤ cut − 1 + spanₐ`,
//! sharing a row with `y′`, so `f_y′ ≤ rₓ′`). Part 0's order gives `cut + lagⱼ ≤ rₓ + lagⱼ ≤ rₓ′ +
//! lagₐ ≤ cut − 1 + spanₐ + lagₐ`, so `j ≤ a`; part 1's gives `f_y − f_y′ ≤ lagᵢ − lagₖ` with
//! `f_y ≥ cut`, so `lagᵢ ≥ lagₖ + 1 − spanₐ ≥ lagₐ + 1`, so `i > a`: then `i < j ≤ a < i`. The other
//! way round the same steps give `j ≤ a` and `lagₖ ≤ lagᵢ + spanᵢ + spanⱼ − 1 − spanₖ`, while
//! `i < j ≤ a < k` gives `lagₖ ≥ lagᵢ + spanᵢ + spanⱼ`. (Also checked on a simulation of the two
//! parts for every cut of short grids and several of tall ones, each part running ahead, by turns
//! and at random, and on threads.) When the parts sweep towards the cut, they meet there at the end
//! of a pass; the solver turns them round every pass, so that each pass starts on the rows the one
//! before ended on, and keeps each part on the same thread, whose caches still hold those rows.

use std::ops::Range;

use crate::fast::pipeline::Progress;

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

/// The plan of two parts of a wavefront that run at once, each over its own rows, in opposite
/// directions, waiting for each other only where their strips share a row across the cut between
/// them (see the module documentation). Each strip goes to the part that holds its first row.
#[derive(Clone, Debug)]
pub(crate) struct OpposedParts {
    /// The first row of part 1.
    cut: usize,
    /// Whether part 0 sweeps its rows upwards and part 1 downwards (the two leave the cut at the
    /// start); else the other way round (they reach it at the end).
    upward_first: bool,
    /// Per part, in its order, its units that share a row with the other part's: the unit and how
    /// far the other part must have got before it (0: no wait).
    waits: [Vec<(usize, usize)>; 2],
}

impl OpposedParts {
    /// Whether part `part` sweeps upwards.
    fn upward(&self, part: usize) -> bool {
        self.upward_first == (part == 0)
    }

    /// The first rows of the strips part `part` holds.
    fn first_rows(&self, part: usize, rows: usize) -> Range<usize> {
        if part == 0 {
            0..self.cut
        } else {
            self.cut..rows
        }
    }
}

impl Wavefront {
    /// Calls `visit(unit, item, last_row)` for part `part`'s strips of `plan` in its order, `unit`
    /// counting up (step by step, items in order within a step). Downwards, item `i` runs on last row
    /// `r` at step `r − a + lagᵢ` (`a` the part's first row): the order of the module documentation.
    /// Upwards, on first row `f` at step `b − 1 − f + lagᵢ` (`b` the row after the part's last): two
    /// strips of items `i < j` that share a row have `fⱼ ≤ fᵢ + spanᵢ`, so `b − 1 − fᵢ + lagᵢ ≤
    /// b − 1 − fⱼ + lagᵢ + spanᵢ ≤ b − 1 − fⱼ + lagⱼ`: the same order, mirrored. Last rows before
    /// `spanᵢ` are not visited: no strip of a batch ends there (a batch's strips all span its span),
    /// and the wind's first cell row ends on row 1.
    fn opposed_sweep(
        &self,
        plan: &OpposedParts,
        part: usize,
        mut visit: impl FnMut(usize, usize, usize),
    ) {
        let firsts = plan.first_rows(part, self.rows);
        if firsts.is_empty() {
            return;
        }
        let items = self.lags.len();
        let upward = plan.upward(part);
        for t in 0..firsts.len() + self.depth() {
            for (i, (&lag, &span)) in self.lags.iter().zip(&self.spans).enumerate() {
                let Some(step) = t.checked_sub(lag) else {
                    continue;
                };
                let first = if upward {
                    (firsts.end - 1).checked_sub(step)
                } else {
                    (firsts.start + step).checked_sub(span)
                };
                if let Some(first) = first.filter(|f| firsts.contains(f) && f + span < self.rows) {
                    visit(t * items + i + 1, i, first + span);
                }
            }
        }
    }

    /// The unit of item `i`'s strip on last row `row` in part `part` of `plan`, as
    /// [`opposed_sweep`](Wavefront::opposed_sweep) counts them, if that part holds it.
    fn opposed_unit(
        &self,
        plan: &OpposedParts,
        part: usize,
        i: usize,
        row: usize,
    ) -> Option<usize> {
        let first = row.checked_sub(self.spans[i])?;
        let firsts = plan.first_rows(part, self.rows);
        if !firsts.contains(&first) || row >= self.rows {
            return None;
        }
        let step = if plan.upward(part) {
            firsts.end - 1 - first
        } else {
            row - firsts.start
        };
        Some((step + self.lags[i]) * self.lags.len() + i + 1)
    }

    /// The plan of two parts cut at row `cut`, part 0 sweeping upwards when `upward_first` (part 1
    /// then downwards: the two leave the cut at the start), else downwards (the two reach the cut at
    /// the end). For every pair of strips of different items that share a row across the cut, the
    /// strip of the later item waits until the other part has run the earlier one. A cut at row 0
    /// or at `rows` leaves one part every row and the other none.
    pub fn opposed_parts(&self, cut: usize, upward_first: bool) -> OpposedParts {
        let mut plan = OpposedParts {
            cut: cut.min(self.rows),
            upward_first,
            waits: [Vec::new(), Vec::new()],
        };
        let most_span = self.spans.iter().copied().max().unwrap_or(0);
        // Part 0's strips touch rows below `cut + most_span`, part 1's rows from `cut` on.
        let zone = plan.cut..(plan.cut + most_span).min(self.rows);
        // Per part and row of the zone: the latest unit that touches it, among the items so far.
        let mut latest = [vec![0; zone.len()], vec![0; zone.len()]];
        let mut touching: Vec<(usize, usize, Range<usize>)> = Vec::new();
        for (i, &span) in self.spans.iter().enumerate() {
            // Item `i`'s strips that touch the zone: last rows from its first row to its last plus
            // the span; each in the part that holds its first row.
            touching.clear();
            for row in zone.start.max(span)..(zone.end + span).min(self.rows) {
                let part = usize::from(row - span >= plan.cut);
                if let Some(unit) = self.opposed_unit(&plan, part, i, row) {
                    let touched = (row - span).max(zone.start)..(row + 1).min(zone.end);
                    touching.push((part, unit, touched));
                }
            }
            for (part, unit, touched) in &touching {
                let other = &latest[1 - part];
                let needed = touched.clone().map(|row| other[row - zone.start]).max();
                plan.waits[*part].push((*unit, needed.unwrap_or(0)));
            }
            for (part, unit, touched) in &touching {
                for row in touched.clone() {
                    let latest = &mut latest[*part][row - zone.start];
                    *latest = (*latest).max(*unit);
                }
            }
        }
        for waits in &mut plan.waits {
            waits.sort_unstable();
        }
        plan
    }

    /// Runs `work(item, last_row)` for part `part` (0 or 1) of `plan` in its order, waiting for the
    /// other part where `plan` says and telling it how far this one has got in `progress`'s counter
    /// `part` (both counters reset beforehand, [`Progress::reset_counters`]). The two parts must run at
    /// once, on threads of their own; if one panics, the other panics too.
    pub fn run_opposed_part(
        &self,
        plan: &OpposedParts,
        part: usize,
        progress: &Progress,
        mut work: impl FnMut(usize, usize),
    ) {
        let poison = progress.poison_if_unwinding();
        let waits = &plan.waits[part];
        let (mut next, mut seen) = (0, 0);
        self.opposed_sweep(plan, part, |unit, i, row| {
            let shared = waits.get(next).is_some_and(|&(u, _)| u == unit);
            if shared && seen < waits[next].1 {
                seen = progress.wait_at_least(1 - part, waits[next].1);
            }
            work(i, row);
            if shared {
                progress.publish(part, unit);
                next += 1;
            }
        });
        progress.publish(part, usize::MAX);
        poison.disarm();
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

    /// Every pair of strips that share a row, the later in the joint order of `spans` (item `j > i`),
    /// as `(i, row_i, j, row_j)`.
    fn sharing_pairs(spans: &[usize], rows: usize) -> Vec<(usize, usize, usize, usize)> {
        let mut pairs = Vec::new();
        for (i, &span_i) in spans.iter().enumerate() {
            for ri in span_i..rows {
                for (j, &span_j) in spans.iter().enumerate().skip(i + 1) {
                    for rj in (ri - span_i).max(span_j)..(ri + span_j + 1).min(rows) {
                        pairs.push((i, ri, j, rj));
                    }
                }
            }
        }
        pairs
    }

    /// Items of a sub-step's wavefront as the solver makes them: the wind, the prediction, a sweep's
    /// batches and its end; `substeps` of them one after another.
    fn substep_spans(substeps: usize) -> Vec<usize> {
        [1, 0, 0, 0, 2, 2, 1, 1, 1, 1, 1, 1, 0, 0, 0].repeat(substeps)
    }

    /// The order two opposed parts run their units in when the parts advance as `pick` chooses
    /// (given the step of the simulation, which part to try first), each waiting as
    /// [`Wavefront::run_opposed_part`] does, but for part `ignoring`, which does not wait: per unit
    /// (item, last row), its place in the joint order. `None` if the parts wait for each other for
    /// ever.
    fn opposed_order(
        plan: &Wavefront,
        halves: &OpposedParts,
        ignoring: Option<usize>,
        pick: impl Fn(usize) -> usize,
    ) -> Option<HashMap<(usize, usize), usize>> {
        let sequences: [Vec<(usize, usize, usize)>; 2] = std::array::from_fn(|part| {
            let mut units = Vec::new();
            plan.opposed_sweep(halves, part, |unit, i, row| {
                assert_eq!(plan.opposed_unit(halves, part, i, row), Some(unit));
                units.push((unit, i, row));
            });
            units
        });
        let (mut next, mut zone_next, mut published) = ([0; 2], [0; 2], [0; 2]);
        let mut order = HashMap::new();
        for clock in 0.. {
            if next[0] == sequences[0].len() && next[1] == sequences[1].len() {
                break;
            }
            let ready = |part: usize, zone_next: &[usize; 2], published: &[usize; 2]| {
                let Some(&(unit, _, _)) = sequences[part].get(next[part]) else {
                    return false;
                };
                match halves.waits[part].get(zone_next[part]) {
                    Some(&(u, needed)) if u == unit && ignoring != Some(part) => {
                        published[1 - part] >= needed
                    }
                    _ => true,
                }
            };
            let first = pick(clock);
            let part = [first, 1 - first]
                .into_iter()
                .find(|&p| ready(p, &zone_next, &published))?;
            let (unit, i, row) = sequences[part][next[part]];
            assert!(
                order.insert((i, row), clock).is_none(),
                "({i}, {row}) ran twice"
            );
            if halves.waits[part]
                .get(zone_next[part])
                .is_some_and(|&(u, _)| u == unit)
            {
                published[part] = unit;
                zone_next[part] += 1;
            }
            next[part] += 1;
            if next[part] == sequences[part].len() {
                published[part] = usize::MAX;
            }
        }
        Some(order)
    }

    /// Two opposed parts run every strip once and every pair of strips that share a row in item
    /// order, whichever part runs ahead, and never wait for each other for ever: the solver's sweeps
    /// (one and three) and odd mixtures of spans, tall and short grids, cuts at every row of a short
    /// grid and at the middle and near the edges of a tall one, both ways round. Checked on a
    /// simulation of the two parts without threads, each advancing as far as it can before the
    /// other, in turns, and at random; where a part has waits, the order breaks without them.
    #[test]
    fn two_opposed_parts_run_every_pair_of_strips_sharing_a_row_in_item_order() {
        let sweep = [0, 0, 2, 2, 1, 1, 1, 1, 1, 1, 0, 0, 0];
        let cases: Vec<Vec<usize>> = vec![
            substep_spans(1),
            substep_spans(3),
            sweep.repeat(3),
            vec![2, 0, 1, 2, 0, 0, 2],
            vec![1],
            vec![0, 0],
        ];
        // A fixed sequence of picks, for the parts to run ahead of each other at random.
        let mut seed = 0x9E37_79B9_u64;
        let random: Vec<usize> = (0..100_000)
            .map(|_| {
                seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (seed >> 33) as usize % 2
            })
            .collect();
        let picks: [&dyn Fn(usize) -> usize; 4] = [&|_| 0, &|_| 1, &|clock| clock % 2, &|clock| {
            random[clock % random.len()]
        }];
        let mut parts_with_waits = 0;
        for spans in cases {
            for rows in [2, 3, 4, 5, 6, 7, 30, 61] {
                let plan = Wavefront::new(spans.clone(), rows);
                let pairs = sharing_pairs(&spans, rows);
                let cuts: Vec<usize> = if rows <= 7 {
                    (0..=rows).collect()
                } else {
                    vec![0, 1, 2, rows / 2, rows - 2, rows - 1, rows]
                };
                for cut in cuts {
                    for upward_first in [false, true] {
                        let halves = plan.opposed_parts(cut, upward_first);
                        let what = format!(
                            "spans {spans:?}, {rows} rows, cut {cut}, part 0 upward {upward_first}"
                        );
                        for pick in picks {
                            let order = opposed_order(&plan, &halves, None, pick)
                                .unwrap_or_else(|| panic!("{what}: the parts wait for ever"));
                            for (i, &span) in spans.iter().enumerate() {
                                for row in span..rows {
                                    assert!(order.contains_key(&(i, row)), "{what}: ({i}, {row})");
                                }
                            }
                            for &(i, ri, j, rj) in &pairs {
                                assert!(
                                    order[&(i, ri)] < order[&(j, rj)],
                                    "{what}: ({i}, {ri}) not before ({j}, {rj})"
                                );
                            }
                        }
                        // A part that runs ahead without its waits runs some strip before one of
                        // an earlier item that shares a row with it.
                        for part in [0, 1] {
                            if halves.waits[part].iter().all(|&(_, needed)| needed == 0) {
                                continue;
                            }
                            parts_with_waits += 1;
                            let order = opposed_order(&plan, &halves, Some(part), |_| part)
                                .expect("a part that does not wait runs to its end");
                            assert!(
                                pairs
                                    .iter()
                                    .any(|&(i, ri, j, rj)| order[&(i, ri)] > order[&(j, rj)]),
                                "{what}: part {part}'s waits are not needed"
                            );
                        }
                    }
                }
            }
        }
        assert!(parts_with_waits > 100, "{parts_with_waits} parts wait");
    }

    /// Two opposed parts on real threads, waiting as [`Wavefront::run_opposed_part`] does, run every
    /// strip once and every pair that shares a row in item order: one and three sub-steps, both ways
    /// round, with a slow part 0 and with a slow part 1.
    #[test]
    fn two_opposed_parts_on_threads_run_every_pair_sharing_a_row_in_item_order() {
        use std::sync::Mutex;
        use std::sync::atomic::{AtomicUsize, Ordering};
        let rows = 40;
        for substeps in [1, 3] {
            let spans = substep_spans(substeps);
            let plan = Wavefront::new(spans.clone(), rows);
            for upward_first in [false, true] {
                let halves = plan.opposed_parts(rows / 2, upward_first);
                for slow_part in [0, 1] {
                    let mut progress = Progress::default();
                    progress.reset_counters(2);
                    let clock = AtomicUsize::new(0);
                    let log: Vec<Mutex<Vec<usize>>> = (0..spans.len() * rows)
                        .map(|_| Mutex::new(Vec::new()))
                        .collect();
                    std::thread::scope(|scope| {
                        for part in 0..2 {
                            let (plan, halves, progress, clock, log) =
                                (&plan, &halves, &progress, &clock, &log);
                            scope.spawn(move || {
                                plan.run_opposed_part(halves, part, progress, |i, row| {
                                    let slow = if part == slow_part { 300 } else { 0 };
                                    for _ in 0..(row * 7 + i * 13) % 50 + slow {
                                        std::hint::spin_loop();
                                    }
                                    let now = clock.fetch_add(1, Ordering::SeqCst);
                                    log[i * rows + row].lock().unwrap().push(now);
                                });
                            });
                        }
                    });
                    let ran: Vec<Vec<usize>> = log
                        .into_iter()
                        .map(|runs| runs.into_inner().unwrap())
                        .collect();
                    for (i, &span) in spans.iter().enumerate() {
                        for row in 0..rows {
                            let runs = ran[i * rows + row].len();
                            assert_eq!(
                                runs,
                                usize::from(row >= span),
                                "({i}, {row}) ran {runs} times"
                            );
                        }
                    }
                    for (i, ri, j, rj) in sharing_pairs(&spans, rows) {
                        assert!(
                            ran[i * rows + ri][0] < ran[j * rows + rj][0],
                            "{substeps} sub-steps, part 0 upward {upward_first}, slow part \
                             {slow_part}: ({i}, {ri}) after ({j}, {rj})"
                        );
                    }
                }
            }
        }
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
