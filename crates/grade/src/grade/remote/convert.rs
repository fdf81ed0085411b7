//! The grader's types and the API crate's (`springlab_homework`): the same fields, converted
//! field by field for each call and each answer.

use glam::DVec3;
use springlab_homework as api;
use springlab_homework::wire::{Reader, Wire, WireError};

use super::super::assignments::{
    Body, ContactCoefficients, Mass, Particle, Rope, Spring, SpringSetup, State,
};
use crate::physics::SpringKind;

pub(super) fn api_vec(v: DVec3) -> api::DVec3 {
    api::DVec3::new(v.x, v.y, v.z)
}

pub(super) fn local_vec(v: api::DVec3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

pub(super) fn api_vecs(v: &[DVec3]) -> Vec<api::DVec3> {
    v.iter().copied().map(api_vec).collect()
}

pub(super) fn local_vecs(v: Vec<api::DVec3>) -> Vec<DVec3> {
    v.into_iter().map(local_vec).collect()
}

/// A `Vec<DVec3>` in its wire form read straight into the grader's vectors: one length check
/// for the list, no list of the API's vectors in between (a body's lists are thousands long).
pub(super) fn take_vecs(r: &mut Reader<'_>) -> Result<Vec<DVec3>, WireError> {
    let mut out = Vec::new();
    read_vecs_into(r, &mut out)?;
    Ok(out)
}

/// [`take_vecs`] into `out` (its memory reused; its entries replaced).
pub(super) fn read_vecs_into(r: &mut Reader<'_>, out: &mut Vec<DVec3>) -> Result<(), WireError> {
    let n = usize::take(r)?;
    let size = n
        .checked_mul(24)
        .ok_or_else(|| WireError(format!("a list of {n} vectors")))?;
    let bytes = r.bytes(size)?;
    let f = |b: &[u8], i: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&b[8 * i..8 * i + 8]);
        f64::from_le_bytes(a)
    };
    out.clear();
    out.extend(
        bytes
            .chunks_exact(24)
            .map(|b| DVec3::new(f(b, 0), f(b, 1), f(b, 2))),
    );
    Ok(())
}

pub(super) fn api_spring(s: &Spring) -> api::Spring {
    api::Spring {
        a: s.a,
        b: s.b,
        rest_length: s.rest_length,
        stiffness: s.stiffness,
        damping: s.damping,
    }
}

pub(super) fn local_spring(s: &api::Spring) -> Spring {
    Spring {
        a: s.a,
        b: s.b,
        rest_length: s.rest_length,
        stiffness: s.stiffness,
        damping: s.damping,
    }
}

pub(super) fn api_rope(r: &Rope) -> api::Rope {
    api::Rope {
        masses: r
            .masses
            .iter()
            .map(|m| api::Mass {
                position: api_vec(m.position),
                velocity: api_vec(m.velocity),
                last_position: api_vec(m.last_position),
                mass: m.mass,
                pinned: m.pinned,
            })
            .collect(),
        springs: r.springs.iter().map(api_spring).collect(),
    }
}

pub(super) fn local_rope(r: &api::Rope) -> Rope {
    Rope {
        masses: r
            .masses
            .iter()
            .map(|m| Mass {
                position: local_vec(m.position),
                velocity: local_vec(m.velocity),
                last_position: local_vec(m.last_position),
                mass: m.mass,
                pinned: m.pinned,
            })
            .collect(),
        springs: r.springs.iter().map(local_spring).collect(),
    }
}

pub(super) fn api_state(s: &State) -> api::State {
    api::State {
        x: api_vecs(&s.x),
        v: api_vecs(&s.v),
    }
}

pub(super) fn local_state(s: api::State) -> State {
    State {
        x: local_vecs(s.x),
        v: local_vecs(s.v),
    }
}

pub(super) fn local_setup(s: &api::SpringSetup) -> SpringSetup {
    SpringSetup {
        a: s.a,
        b: s.b,
        kind: match s.kind {
            api::SpringKind::Struct => SpringKind::Struct,
            api::SpringKind::Shear => SpringKind::Shear,
            api::SpringKind::Bend => SpringKind::Bend,
        },
    }
}

pub(super) fn api_particle(p: &Particle) -> api::Particle {
    api::Particle {
        x: api_vec(p.x),
        v: api_vec(p.v),
        force: api_vec(p.force),
    }
}

pub(super) fn local_particle(p: &api::Particle) -> Particle {
    Particle {
        x: local_vec(p.x),
        v: local_vec(p.v),
        force: local_vec(p.force),
    }
}

pub(super) fn api_contact(c: &ContactCoefficients) -> api::ContactCoefficients {
    api::ContactCoefficients {
        epsilon: c.epsilon,
        restitution: c.restitution,
        friction: c.friction,
    }
}

pub(super) fn api_body(b: &Body) -> api::Body {
    api::Body {
        x: api_vec(b.x),
        v: api_vec(b.v),
        inverse_mass: b.inverse_mass,
    }
}

pub(super) fn local_body(b: &api::Body) -> Body {
    Body {
        x: local_vec(b.x),
        v: local_vec(b.v),
        inverse_mass: b.inverse_mass,
    }
}
