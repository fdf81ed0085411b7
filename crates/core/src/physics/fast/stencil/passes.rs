//! The streaming loop of the stencil (see the parent module's docs): the per-thread scratch
//! buffers, the structure-of-arrays window, pass 1 and pass 2 of each tile (`range_body`), and
//! the end of pass 2 for each chunk (`finish`: total force, acceleration, an integrator's stage,
//! the dissipated power), with the loads and stores of chunks and force rings.

use super::contacts::*;
#[allow(clippy::wildcard_imports)]
use super::*;
pub(super) use crate::physics::lanes::{load_chunk, load_padded, store_chunk};

impl Output<'_> {
    /// How many of `outs` this output writes (always the first ones), and whether `outs[2]`
    /// is optional (written when not empty).
    pub(super) fn outputs(&self) -> (usize, bool) {
        match self {
            Output::Add | Output::Forces(_) | Output::Accelerations(_) => (1, false),
            Output::Power(_) => (0, false),
            Output::Step {
                update: Update::Euler { .. },
                ..
            } => (2, true),
            Output::Step { .. } => (2, false),
        }
    }

    /// Panics when a slice this output reads is shorter than `n`.
    pub(super) fn check(&self, n: usize) {
        let dynamics = match self {
            Output::Add => return,
            Output::Forces(d) | Output::Accelerations(d) | Output::Power(d) => d,
            Output::Step {
                dynamics, update, ..
            } => {
                match update {
                    Update::SemiImplicitEuler { .. }
                    | Update::Euler {
                        base: Base::Input, ..
                    } => {}
                    Update::Euler {
                        base: Base::InPlace,
                        ..
                    } => {}
                    Update::Euler {
                        base: Base::Slices(x, v),
                        ..
                    } => assert!(x.len() >= n && v.len() >= n, "base state too short"),
                    Update::Rk4 { a, v, .. } => assert!(
                        a.iter().chain(v).all(|s| s.len() >= n),
                        "RK4 slopes too short"
                    ),
                }
                dynamics
            }
        };
        assert!(
            dynamics.mass.len() >= n && dynamics.inv_mass.len() >= n,
            "masses too short"
        );
    }
}

/// The first `len` values of `rest` (all of them when shorter), which keeps the others.
pub(super) fn take<'a>(rest: &mut &'a mut [DVec3], len: usize) -> &'a mut [DVec3] {
    let len = len.min(rest.len());
    let (mine, others) = std::mem::take(rest).split_at_mut(len);
    *rest = others;
    mine
}

/// `o[..n]` when `keep`, else `o[..0]`.
pub(super) fn cut(o: &mut [DVec3], keep: bool, n: usize) -> &mut [DVec3] {
    if keep { &mut o[..n] } else { &mut o[..0] }
}

/// The outputs `output` writes (`Output::outputs`), each cut to `n` particles, the others to
/// nothing; checks that `output`'s own arrays hold `n` particles.
pub(super) fn outputs_for<'o>(
    output: &Output,
    outs: [&'o mut [DVec3]; 3],
    n: usize,
) -> [&'o mut [DVec3]; 3] {
    let [o0, o1, o2] = outs;
    let (count, optional) = output.outputs();
    let outs = [
        cut(o0, count > 0, n),
        cut(o1, count > 1, n),
        cut(o2, optional && !o2.is_empty(), n),
    ];
    output.check(n);
    outs
}

/// One part's pieces of the outputs: `outs[k][i]` and `power[2 i..]` belong to the part's
/// particle `q0 + i`; `groups[2 LANES j..]` to the `j`-th power group that starts in the part
/// ([`PowerMode::Groups`]).
pub(super) struct Part<'o> {
    pub(super) outs: [&'o mut [DVec3]; 3],
    pub(super) power: &'o mut [f64],
    pub(super) groups: &'o mut [f64],
}

/// Where a range puts its chunks' dissipated power (`(dampers and drag, contact)`, W, lane by
/// lane): see [`Stencil::sum_power`] for the sum it is part of.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum PowerMode {
    /// Every chunk's into the part's buffer (`Part::power`).
    #[default]
    Buffer,
    /// The range is a whole pass: its groups summed in registers, and the groups' sums into
    /// `Scratch::power_sums` (`P` of [`Stencil::sum_power`]).
    Total,
    /// The range is a part of a team's pass: the chunks before the first group that starts in
    /// it into the buffer (they continue the previous part's group), each group that starts in
    /// it summed in registers (to its end or the part's) into `Part::groups`.
    Groups,
}

/// Scratch buffers of one thread (reused, so steps do not allocate).
#[derive(Default)]
pub(super) struct Scratch {
    /// Positions `x`, `y`, `z` of the particles `base..` (m), zero past the last particle,
    /// then velocities `v_x`, `v_y`, `v_z` (m/s) in the same layout: six components of `S`
    /// values each, one after the other (`S` a multiple of `LANES`), so that the AVX-512
    /// kernel reaches all six from one pointer and `S`.
    pub(super) xv: Aligned,
    /// Every group's force ring (N), see [`Group::ring_offset`].
    pub(super) ring: Aligned,
    /// Where the next range puts its dissipated power; set back to the buffer by that range.
    pub(super) power_mode: PowerMode,
    /// The pass's sums of [`PowerMode::Total`] (W).
    pub(super) power_sums: [[f64; LANES]; 2],
    /// The bounds of the range's colliders ([`Collider::broad`] at the contact band), made
    /// once per range instead of once per chunk and particle.
    pub(super) broads: Vec<Broad>,
}

/// A buffer of f64 whose used part starts at a 64-byte boundary, so that a chunk of `LANES`
/// values at a multiple of `LANES` is one cache line (a load that straddles two lines costs
/// two).
#[derive(Default)]
pub(super) struct Aligned(pub(super) Vec<f64>);

impl Aligned {
    /// `len` values starting at a 64-byte boundary; grows the buffer (with zeros) if needed.
    pub(super) fn get_mut(&mut self, len: usize) -> &mut [f64] {
        if self.0.len() < len + LANES {
            self.0.resize(len + LANES, 0.0);
        }
        // At most LANES - 1 values to the next 64-byte boundary (f64 are 8-byte aligned).
        let offset = self.0.as_ptr().align_offset(64).min(LANES);
        &mut self.0[offset..offset + len]
    }
}

thread_local! {
    pub(super) static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// One chunk of spring forces: `[fx, fy, fz]` (N), one spring per lane.
pub(super) type Forces<V> = [V; 3];

/// The structure-of-arrays copy of the particles `base..base + len` of one range (zero past
/// the last particle): what the kernels read.
pub(super) struct Window<'a> {
    /// Positions `x`, `y`, `z` (m), each of length `len`.
    pub(super) x: [&'a [f64]; 3],
    /// Velocities (m/s), each of length `len`.
    pub(super) v: [&'a [f64]; 3],
}

impl Window<'_> {
    /// Positions and velocities `[x, y, z, v_x, v_y, v_z]` of the `LANES` particles from window
    /// index `i`: the first ends of every group's springs starting there (loaded once per
    /// chunk, not once per group).
    #[inline(always)]
    pub(super) fn first_ends<V: Lanes>(&self, i: usize) -> [V; 6] {
        // Written out, not with `map`: the closure of `map` would not be inlined, and neither
        // would the AVX-512 loads inside it.
        let [x, y, z] = self.x;
        let [vx, vy, vz] = self.v;
        [
            V::load(lanes(x, i)),
            V::load(lanes(y, i)),
            V::load(lanes(z, i)),
            V::load(lanes(vx, i)),
            V::load(lanes(vy, i)),
            V::load(lanes(vz, i)),
        ]
    }
}

/// The streaming loop of the module docs for particles `q0..q1`, with `springs` computing each
/// chunk of springs (forces, and their dampers' power when `POWER`). Inlined into one copy per
/// instruction set.
///
/// Every call `springs(g, first, w, i, p)` has `p` a multiple of `LANES`, `p < g.starts` and
/// `i = p - base` with `i + g.delta + LANES <= len`: the `LANES` springs starting at `p` and
/// both their ends are inside the window and inside `g`'s padded arrays.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn range_body<V: Lanes, const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
    // The `LANES` springs of a group starting at window index `i` (particle `p`), given the
    // positions and velocities of their first ends: their forces, and their dampers' power.
    springs: impl Fn(&Group, &[V; 6], &Window, usize, usize) -> (Forces<V>, V),
) {
    if q0 >= q1 {
        return;
    }
    let n = st.particles;
    // Structure of arrays for particles base..base + len: the springs starting in the halo
    // (from q0 - reach) up to the chunk that contains q1 - 1, and their second ends.
    let base = q0.saturating_sub(st.reach) / LANES * LANES;
    let len = q1.next_multiple_of(LANES) + st.reach - base;
    let Scratch {
        xv,
        ring,
        power_mode,
        power_sums,
        broads,
    } = s;
    let mode = std::mem::take(power_mode);
    broads.clear();
    if let Output::Forces(d)
    | Output::Accelerations(d)
    | Output::Power(d)
    | Output::Step { dynamics: d, .. } = output
    {
        broads.extend(d.colliders.iter().map(|c| c.broad(d.contact.epsilon)));
    }
    let broads = &broads[..];
    // The power summed here, in registers (`Scratch::power_mode`): the chunks from
    // `chained_from` on, group by group (`open`: the group being summed; `closed`: the sum of
    // the groups before it, for a whole pass). The chunks before go to the buffer.
    let group_len = POWER_GROUP * LANES;
    let chained_from = match mode {
        PowerMode::Buffer => usize::MAX,
        PowerMode::Total => q0,
        PowerMode::Groups => q0.next_multiple_of(group_len),
    };
    let mut open = (V::zero(), V::zero());
    let mut closed = (V::zero(), V::zero());
    let mut groups_done = 0;
    // The open group ends: into the closed groups' sums, or stored as the part's next group.
    #[inline(always)]
    fn close<V: Lanes>(
        mode: PowerMode,
        open: &mut (V, V),
        closed: &mut (V, V),
        groups: &mut [f64],
        done: &mut usize,
    ) {
        if mode == PowerMode::Groups {
            let group = &mut groups[2 * LANES * *done..2 * LANES * (*done + 1)];
            let (dampers, contact) = group.split_at_mut(LANES);
            open.0.store(dampers.try_into().expect("a chunk"));
            open.1.store(contact.try_into().expect("a chunk"));
            *done += 1;
        } else {
            *closed = (closed.0.add(open.0), closed.1.add(open.1));
        }
        *open = (V::zero(), V::zero());
    }
    let stride = len.next_multiple_of(LANES);
    let (xs, vs) = xv.get_mut(6 * stride).split_at_mut(3 * stride);
    let (xs0, rest) = xs.split_at_mut(stride);
    let (xs1, xs2) = rest.split_at_mut(stride);
    let (vs0, rest) = vs.split_at_mut(stride);
    let (vs1, vs2) = rest.split_at_mut(stride);
    let mut xs = [&mut xs0[..len], &mut xs1[..len], &mut xs2[..len]];
    let mut vs = [&mut vs0[..len], &mut vs1[..len], &mut vs2[..len]];
    let ring = ring.get_mut(st.ring_len);
    let real = n.min(base + len) - base;
    let whole = real / LANES * LANES;
    for (i, (x, v)) in x[base + whole..base + real]
        .iter()
        .zip(&v[base + whole..base + real])
        .enumerate()
    {
        let i = whole + i;
        xs[0][i] = x.x;
        xs[1][i] = x.y;
        xs[2][i] = x.z;
        vs[0][i] = v.x;
        vs[1][i] = v.y;
        vs[2][i] = v.z;
    }
    for c in xs.iter_mut().chain(vs.iter_mut()) {
        c[real..].fill(0.0);
    }
    // The whole chunks are copied as the loop goes, a tile ahead of the springs that read them
    // (so the window is still in the first-level cache when they do): before the springs
    // starting below particle `t`, the window up to `need(t)`.
    let need = |t: usize| {
        (t - base + st.reach + LANES)
            .next_multiple_of(LANES)
            .min(whole)
    };
    let mut copied = 0;
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn copy<V: Lanes>(
        x: &[DVec3],
        v: &[DVec3],
        base: usize,
        xs: &mut [&mut [f64]; 3],
        vs: &mut [&mut [f64]; 3],
        copied: &mut usize,
        to: usize,
    ) {
        for i in (*copied..to).step_by(LANES) {
            let p = base + i;
            let xc = V::load_vectors(x[p..p + LANES].try_into().expect("a chunk"));
            let vc = V::load_vectors(v[p..p + LANES].try_into().expect("a chunk"));
            for c in 0..3 {
                xc[c].store((&mut xs[c][i..i + LANES]).try_into().expect("a chunk"));
                vc[c].store((&mut vs[c][i..i + LANES]).try_into().expect("a chunk"));
            }
        }
        *copied = (*copied).max(to);
    }
    copy::<V>(x, v, base, &mut xs, &mut vs, &mut copied, need(q0));
    let w = Window {
        x: [&*xs[0], &*xs[1], &*xs[2]],
        v: [&*vs[0], &*vs[1], &*vs[2]],
    };
    // Halo: the springs that start before q0 and end at q0 or later, into the rings.
    for g in &st.groups {
        let first = q0.saturating_sub(g.delta) / LANES * LANES;
        for p in (first..q0.min(g.starts)).step_by(LANES) {
            let (f, _) = springs(g, &w.first_ends(p - base), &w, p - base, p);
            // SAFETY: `ring` is `ring_len` long, which holds every group's ring.
            unsafe { ring_store(ring, g, p, f) };
        }
    }
    for t0 in (q0..q1).step_by(TILE) {
        let t1 = (t0 + TILE).min(q1);
        copy::<V>(x, v, base, &mut xs, &mut vs, &mut copied, need(t1));
        let w = Window {
            x: [&*xs[0], &*xs[1], &*xs[2]],
            v: [&*vs[0], &*vs[1], &*vs[2]],
        };
        // Pass 1, chunk by chunk: the springs that start here, offset by offset (the groups
        // a chunk has are a prefix of the list), into the rings, and their sum `plus`.
        let mut plus = [[V::zero(); 3]; CHUNKS];
        let mut spring_power = [V::zero(); CHUNKS];
        for (c, p) in (t0..t1).step_by(LANES).enumerate() {
            let first = w.first_ends::<V>(p - base);
            let mut sum = [V::zero(); 3];
            let mut power = V::zero();
            // Every group but near the end (the groups are sorted by δ, so `starts` falls).
            let groups = if p + st.reach < n {
                &st.groups[..]
            } else {
                &st.groups[..st.groups.partition_point(|g| p < g.starts)]
            };
            for g in groups {
                let (f, pw) = springs(g, &first, &w, p - base, p);
                // SAFETY: `ring` is `ring_len` long, which holds every group's ring.
                unsafe { ring_store(ring, g, p, f) };
                for (total, part) in sum.iter_mut().zip(f) {
                    *total = total.add(part);
                }
                if POWER {
                    power = power.add(pw);
                }
            }
            plus[c] = sum;
            spring_power[c] = power;
        }
        // Pass 2: minus the springs that end here (they started δ earlier), gathered offset
        // by offset for the tile's chunks side by side (each chunk's sum adds the offsets in
        // their order). The ring of δ holds at least the last δ + TILE + LANES forces.
        let minus = if t0 >= st.reach {
            // SAFETY: `ring` is `ring_len` long, which holds every group's ring.
            unsafe { second_ends::<V, false>(st, ring, t0) }
        } else {
            // SAFETY: as above.
            unsafe { second_ends::<V, true>(st, ring, t0) }
        };
        for (c, q) in (t0..t1).step_by(LANES).enumerate() {
            let minus = minus[c];
            let sum = [
                plus[c][0].sub(minus[0]),
                plus[c][1].sub(minus[1]),
                plus[c][2].sub(minus[2]),
            ];
            let i = q - base;
            let chunk = Chunk {
                q,
                at: q - q0,
                count: (q1 - q).min(LANES),
                x: components(w.x, i),
                v: components(w.v, i),
            };
            let chained = POWER && q >= chained_from;
            if chained && q > chained_from && q.is_multiple_of(group_len) {
                close(mode, &mut open, &mut closed, part.groups, &mut groups_done);
            }
            let sums = chained.then_some(&mut open);
            if chunk.count == LANES {
                finish::<V, POWER, true>(output, broads, &chunk, sum, spring_power[c], part, sums);
            } else {
                finish::<V, POWER, false>(output, broads, &chunk, sum, spring_power[c], part, sums);
            }
        }
        if let Output::Step {
            after: Some(after), ..
        } = output
        {
            let (a, b) = (t0 - q0, t1 - q0);
            let [xo, vo, _] = &mut part.outs;
            after(&mut xo[a..b], &mut vo[a..b]);
        }
    }
    if POWER && chained_from < q1 {
        close(mode, &mut open, &mut closed, part.groups, &mut groups_done);
    }
    if mode == PowerMode::Total {
        closed.0.store(&mut power_sums[0]);
        closed.1.store(&mut power_sums[1]);
    }
}

/// Chunks of `LANES` particles per tile.
const CHUNKS: usize = TILE / LANES;

/// Pass 2's sums for the tile from particle `t0`: for each of its [`CHUNKS`] chunks `q`, the
/// forces of the springs that end there, `Σ_δ ring_δ[q-δ..q-δ+8]`, added offset by offset in
/// the groups' order (chunks past the end of the range are computed too, from whatever their
/// ring slots hold, and not used). `NEAR_START`: some `q < δ`, whose first `δ - q` lanes have
/// no spring (it would start before particle 0) and are cleared.
///
/// # Safety
/// As [`ring_load`]: `ring` holds every group's ring.
#[inline(always)]
unsafe fn second_ends<V: Lanes, const NEAR_START: bool>(
    st: &Stencil,
    ring: &[f64],
    t0: usize,
) -> [Forces<V>; CHUNKS] {
    let mut minus = [[V::zero(); 3]; CHUNKS];
    if V::FUNNEL {
        for g in &st.groups {
            // The chunks start r values into whole chunks of the ring: load those, aligned
            // (each read by two neighbouring chunks), and funnel each pair.
            let start = t0.wrapping_sub(g.delta);
            let r = start % LANES;
            if r == 0 && !NEAR_START {
                // Whole chunks already (δ a multiple of LANES).
                for (c, sum) in minus.iter_mut().enumerate() {
                    // SAFETY: the caller guarantees the group's ring.
                    let f: Forces<V> = unsafe { ring_load(ring, g, start.wrapping_add(c * LANES)) };
                    for (total, part) in sum.iter_mut().zip(f) {
                        *total = total.add(part);
                    }
                }
                continue;
            }
            let aligned = start.wrapping_sub(r);
            // SAFETY: as above.
            let mut low: Forces<V> = unsafe { ring_load(ring, g, aligned) };
            for (c, sum) in minus.iter_mut().enumerate() {
                let q = t0 + c * LANES;
                // SAFETY: as above.
                let high: Forces<V> =
                    unsafe { ring_load(ring, g, aligned.wrapping_add((c + 1) * LANES)) };
                let mut f = [
                    low[0].funnel(high[0], r),
                    low[1].funnel(high[1], r),
                    low[2].funnel(high[2], r),
                ];
                low = high;
                if NEAR_START && q < g.delta {
                    let k = g.delta - q;
                    f = f.map(|c| c.clear_below(k));
                }
                for (total, part) in sum.iter_mut().zip(f) {
                    *total = total.add(part);
                }
            }
        }
        return minus;
    }
    for g in &st.groups {
        for (c, sum) in minus.iter_mut().enumerate() {
            let q = t0 + c * LANES;
            // SAFETY: the caller guarantees the group's ring.
            let mut f: Forces<V> = unsafe { ring_load(ring, g, q.wrapping_sub(g.delta)) };
            if NEAR_START && q < g.delta {
                // Their ring slots hold other values.
                let k = g.delta - q;
                f = f.map(|c| c.clear_below(k));
            }
            for (total, part) in sum.iter_mut().zip(f) {
                *total = total.add(part);
            }
        }
    }
    minus
}

/// Semi-implicit Euler on a chunk: `v' = v + dt a`, then `x' = x + dt v'` (positions in m,
/// velocities in m/s, accelerations in m/s², `dt` in s in every lane). Returns `(x', v')`.
#[inline(always)]
pub(super) fn semi_implicit_euler<V: Lanes>(
    x: [V; 3],
    v: [V; 3],
    a: [V; 3],
    dt: V,
) -> ([V; 3], [V; 3]) {
    let v_new = [
        v[0].add(dt.mul(a[0])),
        v[1].add(dt.mul(a[1])),
        v[2].add(dt.mul(a[2])),
    ];
    let x_new = [
        x[0].add(dt.mul(v_new[0])),
        x[1].add(dt.mul(v_new[1])),
        x[2].add(dt.mul(v_new[2])),
    ];
    (x_new, v_new)
}

/// One chunk of particles in pass 2: particle `q` (a multiple of `LANES`) is index `at` of the
/// part's outputs; `count` of its `LANES` particles exist; `x`, `v` are the pass's input.
pub(super) struct Chunk<V> {
    pub(super) q: usize,
    pub(super) at: usize,
    pub(super) count: usize,
    pub(super) x: [V; 3],
    pub(super) v: [V; 3],
}

/// Pass 2's end for one chunk: from the spring forces `sum` (N) to what `output` asks for,
/// and the chunk's dissipated power when `POWER`. `WHOLE`: the chunk has `LANES` particles
/// (`chunk.count` is then not read). `sums`: the power is added to these running sums
/// `(dampers and drag, contact)` instead of written to the part's buffer. `broads`: the bounds
/// of the output's colliders, in their order.
#[inline(always)]
pub(super) fn finish<V: Lanes, const POWER: bool, const WHOLE: bool>(
    output: &Output,
    broads: &[Broad],
    chunk: &Chunk<V>,
    sum: [V; 3],
    spring_power: V,
    part: &mut Part,
    sums: Option<&mut (V, V)>,
) {
    let Chunk { q, at, count, x, v } = *chunk;
    // A whole chunk (every one but a range's last): its loads and stores without the test for
    // a short chunk.
    let count = if WHOLE { LANES } else { count };
    let d = match *output {
        Output::Add => {
            let out = &mut part.outs[0][at..];
            let old = load_chunk::<V>(out, count);
            let new = [old[0].add(sum[0]), old[1].add(sum[1]), old[2].add(sum[2])];
            store_chunk(new, out, count);
            return;
        }
        Output::Forces(d) | Output::Accelerations(d) | Output::Power(d) => d,
        Output::Step { dynamics, .. } => dynamics,
    };
    // f = (m g - c v) + F_springs, in the order of `forces`; then the contact force.
    let m = load_padded::<V>(d.mass, q, count);
    let mut f = weight_drag_springs(m, d.gravity, d.drag, v, sum);
    let w = load_padded::<V>(d.inv_mass, q, count);
    let free = V::zero().less_than(w);
    let mut contact_power = V::zero();
    if !d.colliders.is_empty() {
        let candidates = free & may_touch(broads, x);
        if candidates != 0 {
            (f, contact_power) = contact_lanes(&d, broads, x, v, f, candidates);
        }
    }
    if POWER {
        // Drag c |v|² of the free particles, added to the dampers of the springs that start
        // here (see `energy::dissipated_power`).
        let drag = if d.drag == 0.0 {
            V::zero()
        } else {
            let v2 = v[0].mul(v[0]).add(v[1].mul(v[1])).add(v[2].mul(v[2]));
            V::splat(d.drag).mul(v2).select(free)
        };
        if let Some((dampers, contact)) = sums {
            // As `Stencil::sum_power` adds the chunks written below, in the same order.
            *dampers = dampers.add(spring_power.add(drag));
            if !d.colliders.is_empty() {
                *contact = contact.add(contact_power);
            }
        } else {
            let power = &mut part.power[2 * at..2 * at + 2 * LANES];
            let (dampers, contact) = power.split_at_mut(LANES);
            spring_power
                .add(drag)
                .store(dampers.try_into().expect("a chunk"));
            // Without colliders no contact values (`Stencil::sum_power` reads none then).
            if !d.colliders.is_empty() {
                contact_power.store(contact.try_into().expect("a chunk"));
            }
        }
    }
    let a = [f[0].mul(w), f[1].mul(w), f[2].mul(w)];
    match *output {
        Output::Add | Output::Power(_) => {}
        Output::Forces(_) => store_chunk(f, &mut part.outs[0][at..], count),
        Output::Accelerations(_) => store_chunk(a, &mut part.outs[0][at..], count),
        Output::Step { update, .. } => {
            let [xo, vo, ao] = &mut part.outs;
            match update {
                Update::SemiImplicitEuler { dt } => {
                    let (x_new, v_new) = semi_implicit_euler(x, v, a, V::splat(dt));
                    store_chunk(x_new, &mut xo[at..], count);
                    store_chunk(v_new, &mut vo[at..], count);
                }
                Update::Euler { h, base } => {
                    let (bx, bv) = match base {
                        Base::Input => (x, v),
                        Base::Slices(bx, bv) => {
                            (load_chunk(&bx[q..], count), load_chunk(&bv[q..], count))
                        }
                        Base::InPlace => {
                            (load_chunk(&xo[at..], count), load_chunk(&vo[at..], count))
                        }
                    };
                    let h = V::splat(h);
                    // x' = x_b + h v;  v' = v_b + h a.
                    let x_new = [
                        bx[0].add(h.mul(v[0])),
                        bx[1].add(h.mul(v[1])),
                        bx[2].add(h.mul(v[2])),
                    ];
                    let v_new = [
                        bv[0].add(h.mul(a[0])),
                        bv[1].add(h.mul(a[1])),
                        bv[2].add(h.mul(a[2])),
                    ];
                    store_chunk(x_new, &mut xo[at..], count);
                    store_chunk(v_new, &mut vo[at..], count);
                    if !ao.is_empty() {
                        store_chunk(a, &mut ao[at..], count);
                    }
                }
                Update::Rk4 {
                    sixth,
                    a: [a1, a2, a3],
                    v: [v2, v3],
                } => {
                    let (xn, vn) = (
                        load_chunk::<V>(&xo[at..], count),
                        load_chunk::<V>(&vo[at..], count),
                    );
                    let (a1, a2, a3) = (
                        load_chunk::<V>(&a1[q..], count),
                        load_chunk::<V>(&a2[q..], count),
                        load_chunk::<V>(&a3[q..], count),
                    );
                    let (v2, v3) = (
                        load_chunk::<V>(&v2[q..], count),
                        load_chunk::<V>(&v3[q..], count),
                    );
                    let (two, sixth) = (V::splat(2.0), V::splat(sixth));
                    // x' = x_n + dt/6 (k1x + 2 k2x + 2 k3x + k4x), k1x = v_n, k4x = v;
                    // v' = v_n + dt/6 (k1v + 2 k2v + 2 k3v + k4v), k4v = a.
                    // Written out per component, not with `array::from_fn`: its closure would
                    // not be inlined, and the AVX-512 operations inside it would become calls.
                    #[inline(always)]
                    fn weighted<V: Lanes>(two: V, k1: V, k2: V, k3: V, k4: V) -> V {
                        k1.add(two.mul(k2)).add(two.mul(k3)).add(k4)
                    }
                    let x_new: [V; 3] = [
                        xn[0].add(sixth.mul(weighted(two, vn[0], v2[0], v3[0], v[0]))),
                        xn[1].add(sixth.mul(weighted(two, vn[1], v2[1], v3[1], v[1]))),
                        xn[2].add(sixth.mul(weighted(two, vn[2], v2[2], v3[2], v[2]))),
                    ];
                    let v_new: [V; 3] = [
                        vn[0].add(sixth.mul(weighted(two, a1[0], a2[0], a3[0], a[0]))),
                        vn[1].add(sixth.mul(weighted(two, a1[1], a2[1], a3[1], a[1]))),
                        vn[2].add(sixth.mul(weighted(two, a1[2], a2[2], a3[2], a[2]))),
                    ];
                    store_chunk(x_new, &mut xo[at..], count);
                    store_chunk(v_new, &mut vo[at..], count);
                }
            }
        }
    }
}

/// The `x`, `y`, `z` lanes of window arrays (positions or velocities) from index `i`.
#[inline(always)]
pub(super) fn components<V: Lanes>(arrays: [&[f64]; 3], i: usize) -> [V; 3] {
    [
        V::load(lanes(arrays[0], i)),
        V::load(lanes(arrays[1], i)),
        V::load(lanes(arrays[2], i)),
    ]
}

/// `(m g - c v) + F_springs` (N), lane by lane, in the order of `forces`.
#[inline(always)]
pub(super) fn weight_drag_springs<V: Lanes>(
    m: V,
    g: DVec3,
    c: f64,
    v: [V; 3],
    spring: [V; 3],
) -> [V; 3] {
    let c = V::splat(c);
    [
        m.mul(V::splat(g.x)).sub(c.mul(v[0])).add(spring[0]),
        m.mul(V::splat(g.y)).sub(c.mul(v[1])).add(spring[1]),
        m.mul(V::splat(g.z)).sub(c.mul(v[2])).add(spring[2]),
    ]
}

/// Keeps the forces of the chunk of springs starting at `p` (a multiple of `LANES`) in the
/// ring of `g`: component `c` of particle `p` at `ring_offset + c (R + LANES) + p mod R`; and,
/// for lanes without [`Lanes::FUNNEL`] (whose pass 2 reads chunks that start anywhere), the
/// first chunk again after the end (the mirror), so that a read can run across the wrap. With
/// a funnel pass 2 reads whole chunks only and needs no mirror, nor its branch.
///
/// Unchecked (the streaming loop calls it for every chunk of every group, where a bounds check
/// is several instructions besides the three stores).
///
/// # Safety
/// `ring` must hold the group's ring: `g.ring_offset + 3 (g.ring + LANES) <= ring.len()`, as
/// every slice of at least the stencil's `ring_len` does (`range_body` takes that length).
#[inline(always)]
pub(super) unsafe fn ring_store<V: Lanes>(ring: &mut [f64], g: &Group, p: usize, f: Forces<V>) {
    let slot = p & (g.ring - 1);
    let stride = g.ring + LANES;
    debug_assert!(g.ring_offset + 3 * stride <= ring.len());
    // SAFETY: the caller guarantees the group's three components (see above).
    let ring = unsafe { ring.as_mut_ptr().add(g.ring_offset) };
    for (c, part) in f.into_iter().enumerate() {
        let at = c * stride + slot;
        // SAFETY: `at + LANES <= 3 * stride` because `c <= 2` and `slot < R`, inside the
        // group's components; `Lanes::store` writes exactly LANES values.
        part.store(unsafe { &mut *ring.add(at).cast::<[f64; LANES]>() });
        if slot == 0 && !V::FUNNEL {
            // The mirror after the end, so that unaligned reads can run across the wrap (the
            // funnelling lanes read whole chunks only: `second_ends`).
            let mirror = c * stride + g.ring;
            // SAFETY: `mirror + LANES = (c + 1) * stride`, inside the group's components.
            part.store(unsafe { &mut *ring.add(mirror).cast::<[f64; LANES]>() });
        }
    }
}

/// The forces of the `LANES` springs of `g` starting at `p` (taken modulo `R`), from the ring:
/// any `p` where the ring keeps its mirror, a multiple of `LANES` where it does not (lanes with
/// [`Lanes::FUNNEL`], see [`ring_store`]). Unchecked, as [`ring_store`].
///
/// # Safety
/// As [`ring_store`]: `g.ring_offset + 3 (g.ring + LANES) <= ring.len()`.
#[inline(always)]
pub(super) unsafe fn ring_load<V: Lanes>(ring: &[f64], g: &Group, p: usize) -> Forces<V> {
    let slot = p & (g.ring - 1);
    let stride = g.ring + LANES;
    debug_assert!(g.ring_offset + 3 * stride <= ring.len());
    // SAFETY: `g.ring_offset + c * stride + slot + LANES <= g.ring_offset + 3 * stride <=
    // ring.len()` for `c <= 2`, because `slot < R = stride - LANES` (the caller guarantees the
    // last); `Lanes::load` reads exactly LANES values.
    let load = |c: usize| unsafe {
        V::load(&*ring.as_ptr().add(g.ring_offset + c * stride + slot).cast())
    };
    [load(0), load(1), load(2)]
}

impl Stencil {
    /// [`Stencil::write`] with the dissipated power (only with [`Dynamics`]), and its total
    /// `(dampers and drag, contact)` (W) as [`Stencil::sum_power`] adds it from `power` (at
    /// least [`Stencil::power_len`] long). On one part the chunks' power is added in registers
    /// as the pass goes, in the same order, and `power` is not written.
    ///
    /// # Panics
    /// As [`Stencil::write`].
    pub fn write_with_power(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        outs: [&mut [DVec3]; 3],
        power: &mut [f64],
        output: Output,
    ) -> (f64, f64) {
        let parts = self.parallel_parts(Pool::global().threads());
        self.write_with_power_in_parts(x, v, outs, power, output, parts)
    }

    /// [`Stencil::write_with_power`] with the particles split into `parts` ranges (at most
    /// [`MAX_PARTS`]); the same results bit for bit for every `parts`.
    ///
    /// # Panics
    /// As [`Stencil::write`].
    pub fn write_with_power_in_parts(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        outs: [&mut [DVec3]; 3],
        power: &mut [f64],
        output: Output,
        parts: usize,
    ) -> (f64, f64) {
        let contact = output.dynamics().is_some_and(|d| !d.colliders.is_empty());
        if parts > 1 || matches!(output, Output::Add) {
            self.write_in_parts(x, v, outs, power, output, parts);
            return Self::sum_power(&power[..self.power_len()], contact);
        }
        let n = self.particles;
        let (x, v) = (&x[..n], &v[..n]);
        let outs = outputs_for(&output, outs, n);
        let mut part = Part {
            outs,
            power: &mut [],
            groups: &mut [],
        };
        let sums = SCRATCH.with(|s| {
            let s = &mut *s.borrow_mut();
            s.power_mode = PowerMode::Total;
            s.power_sums = [[0.0; LANES]; 2];
            self.range(s, x, v, 0, n, &mut part, &output);
            s.power_mode = PowerMode::Buffer;
            s.power_sums
        });
        Self::power_total(&sums, contact)
    }
}

impl<'a> Output<'a> {
    /// The weight, drag, contact and masses the output reads, if any.
    #[must_use]
    pub fn dynamics(&self) -> Option<&Dynamics<'a>> {
        match self {
            Output::Add => None,
            Output::Forces(d) | Output::Accelerations(d) | Output::Power(d) => Some(d),
            Output::Step { dynamics, .. } => Some(dynamics),
        }
    }
}
