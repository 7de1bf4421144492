//! The sub-step advice: how many sub-steps a step needs so that every pair that may touch
//! gets its contact resolved.

use super::*;

impl DiscreteContacts {
    /// Sub-steps this step needs: the Hertz contact time
    /// `t_H = 2.87 (m*² / (R* E*² v0))^(1/5)` of every handled candidate pair, at its current
    /// approach speed, must span [`SUBSTEPS_PER_CONTACT`] sub-steps (or the number set with
    /// [`with_substeps_per_contact`](Self::with_substeps_per_contact)). A pair whose Hertz
    /// indentation `(15 m* v0² / (16 E* √R*))^(2/5)` exceeds a fraction (by default half, see
    /// [`with_indentation_limit`](Self::with_indentation_limit)) of the smaller body's smallest
    /// half-extent is refused
    /// with [`Error::ContactTooSoft`].
    ///
    /// With friction through the tangential spring, its oscillation counts too: stiffness
    /// `κ k_n` against the tangential effective mass `m_t` (`1/m_t = Σ 1/m + r²/I_min` over the
    /// bodies, `r` the bounding radius; `2/7 m*` for two spheres), so its contact time is
    /// `t_H √(m_t / (κ m*))`, about half of `t_H`. Live contacts also count with their own
    /// stiffness `k_n = dF_n/dd` from their last evaluation (a face resting on a face is far
    /// stiffer than the Hertz sphere of the bounding radii): each pair's normal half-period
    /// `π √(m*/k_n)`, and the half-period of the highest frequency of all of them together —
    /// a network of springs `k_n` along each normal and, with the spring, `κ k_n` across it,
    /// at each contact point's levers, and each overlap's resistance to tilting, with every
    /// body's mass and inertia tensor (see `network`:
    /// a pile vibrates faster than any of its pairs, a face's contact under the centre slower
    /// than a lever of the bounding radius would make it). Where no estimate comes out, each
    /// live contact counts its spring alone instead, `π √(m_t/(κ k_n))`. These need stability
    /// and a steady hold, not a restitution's accuracy: each gets [`MIN_SUBSTEPS_PER_CONTACT`]
    /// sub-steps at the default [`SUBSTEPS_PER_CONTACT`], fewer in proportion when fewer sub-steps
    /// per contact are set, never fewer than [`STABLE_SUBSTEPS_PER_HALF_PERIOD`].
    ///
    /// A live contact whose stiffness is not finite (its force law overflowed) is reported
    /// with [`Error::NonFinite`], naming the pair.
    ///
    /// The user's `filter_contact_pair` hook is not consulted here (a pair it would exclude
    /// still counts, so the advice never falls short); [`step_with_events`](Self::step_with_events)
    /// consults it.
    pub fn substeps(&self, world: &PhysicsWorld, dt: engine::math::Real) -> Result<usize> {
        self.substeps_with(world, &(), real(dt))
    }

    /// [`substeps`](Self::substeps) with the user's hooks filtering the pairs.
    ///
    /// Under [`Integration::Implicit`] only the liquid film divides the world's step: resting
    /// contacts are taken implicitly at any step, and each impact is resolved in sub-steps of
    /// its own (see `impacts`), which [`pair_limits`](Self::pair_limits) sets.
    pub(super) fn substeps_with(
        &self,
        world: &PhysicsWorld,
        hooks: &dyn PhysicsHooks,
        dt: Real,
    ) -> Result<usize> {
        let implicit = self.implicit();
        let spring = self.tangential == TangentialLaw::Spring && !self.friction.is_none();
        // `None` where no estimate comes out (no live contact between moving bodies, or a
        // degenerate network): each live contact's spring then counts alone.
        let network = if implicit { None } else { network::highest_frequency(self, world, spring) };
        let mut limits = Limits::default();
        for (ca, cb) in self.lookahead_pairs(world, hooks, dt)? {
            let motions = (Self::kinematics(world, ca), Self::kinematics(world, cb));
            let film_only = implicit;
            self.pair_limits(world, (ca, cb), &motions, network.is_some(), film_only, &mut limits)?;
        }
        // The live contacts' network: its highest frequency's half-period, as a pair's own.
        if let Some((omega2, pair)) = network {
            let half_period = core::f64::consts::PI / omega2.sqrt();
            limits.resolve(half_period / self.per_half_period(), half_period, pair);
        }
        self.divide(dt, &limits)
    }

    /// Sub-steps a live contact's own oscillation gets per half-period at least (see
    /// [`substeps`](Self::substeps)).
    pub(super) fn per_half_period(&self) -> Real {
        (MIN_SUBSTEPS_PER_CONTACT * self.substeps_per_contact / SUBSTEPS_PER_CONTACT)
            .max(STABLE_SUBSTEPS_PER_HALF_PERIOD)
    }

    /// Adds to `limits` what the pair `(ca, cb)`, its colliders moving as `motions`, asks of a
    /// sub-step (see [`substeps`](Self::substeps)): the Hertz contact time at its approach
    /// speed (refused as too soft where Hertz's indentation is beyond the limit), its
    /// tangential spring's, a live contact's own stiffness's (its spring's too unless the
    /// network holds it, `in_network`), the film's relaxation, and its motion against the
    /// coordinates' spacing. `film_only`: the film's relaxation and the motion alone.
    pub(super) fn pair_limits(
        &self,
        world: &PhysicsWorld,
        (ca, cb): (ColliderHandle, ColliderHandle),
        (a, b): &(ColliderMotion, ColliderMotion),
        in_network: bool,
        film_only: bool,
        limits: &mut Limits,
    ) -> Result<()> {
        let named = |(a, b): Pair| format!("colliders {a:?} and {b:?}");
        let (ha, hb) = (&self.handled[&ca], &self.handled[&cb]);
        let (pa, ka, ma, pb, kb, mb) = (a.pose, a.kinematics, a.mass, b.pose, b.kinematics, b.mass);
        let m_star = 1.0 / (1.0 / ma + 1.0 / mb);
        // Two immovable bodies, or a mass rapier has not computed yet (before its first step).
        if !(m_star.is_finite() && m_star > 0.0) {
            return Ok(());
        }
        // The film's damping `c` at its minimum gap: explicit steps resolve `m*/c`.
        let film =
            self.lubrication.as_ref().map(|lub| m_star / lub.max_damping(ha.film_radius_with(hb)));
        if let Some(relaxation) = film.filter(|t| t.is_finite() && *t > 0.0) {
            limits.resolve(relaxation, relaxation, (ca, cb));
        }
        let spring = self.tangential == TangentialLaw::Spring && !self.friction.is_none();
        let per_half_period = self.per_half_period();
        let r_star = 1.0 / (1.0 / ha.radius + 1.0 / hb.radius);
        let e_star = effective_modulus(&ha.material, &hb.material);
        // Relative speed bound: centre speeds plus rim speeds of the bounded bodies.
        let rim = |k: &BodyKinematics, r: Real| {
            if r.is_finite() {
                k.angvel.length() * r
            } else {
                0.0
            }
        };
        let rims = rim(&ka, ha.radius) + rim(&kb, hb.radius);
        // A live contact is resolved for the impact it began with: it slows through every
        // speed down to zero at its deepest, where Hertz's time at the speed then would be
        // longer than the impact's.
        let live = self.contact(ca, cb);
        let v0 = ((ka.linvel - kb.linvel).length() + rims)
            .max(live.map_or(0.0, |s| s.reference_approach_speed))
            .max(AT_REST_SPEED);
        let t_h = hertz_contact_time(m_star, r_star, e_star, v0);
        // Hertz's deepest indentation, from the speed along the line from A to B (a body
        // sliding past another does not indent it); beyond the limit the bodies pass through.
        let (a, b) = (pa.transform_point(ha.centre), pb.transform_point(hb.centre));
        let towards_b = if let Some(n) = ha.wall_normal(&pa, b) {
            n
        } else if let Some(n) = hb.wall_normal(&pb, a) {
            -n
        } else {
            let image = self.periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(a, b));
            (b + image - a).normalize_or_zero()
        };
        let approach = if towards_b == Vector::ZERO {
            (ka.linvel - kb.linvel).length() + rims
        } else {
            (ka.linvel - kb.linvel).dot(towards_b).max(0.0) + rims
        };
        let v_normal = approach.max(AT_REST_SPEED);
        // The largest coordinate of the bodies that move, whose spacing in rapier's numbers
        // bounds what a sub-step can resolve.
        let largest = [(pa.translation, ma), (pb.translation, mb)]
            .iter()
            .filter(|(_, m)| m.is_finite())
            .map(|(x, _)| x.abs().max_element())
            .fold(0.0, Real::max);
        let spacing = coordinate_spacing(largest, boundary::EPSILON);
        // The impact to resolve: a live contact's is the one it began with, a pair apart's its
        // approach now.
        let impact = live.map_or(approach, |s| s.reference_approach_speed);
        if impact >= AT_REST_SPEED
            && limits.coarsest.as_ref().is_none_or(|c| impact / spacing < c.0)
        {
            limits.coarsest = Some((impact / spacing, impact, largest, spacing, (ca, cb)));
        }
        if film_only {
            return Ok(());
        }
        let depth = hertz_max_indentation(m_star, r_star, e_star, v_normal);
        let limit = self.indentation_limit * ha.half_size.min(hb.half_size);
        if depth > limit {
            return Err(Error::ContactTooSoft {
                pair: named((ca, cb)),
                speed: v_normal,
                indentation: depth,
                limit,
            });
        }
        limits.resolve(t_h / self.substeps_per_contact, t_h, (ca, cb));
        let mut resolve = |t: Real| {
            if t.is_finite() && t > 0.0 {
                limits.resolve(t / per_half_period, t, (ca, cb));
            }
        };
        // The spring's stiffness ratio and tangential mass.
        let tangential = spring.then(|| {
            (
                stiffness_ratio(&ha.material, &hb.material),
                Self::tangential_mass(world, (ca, ha), (cb, hb)),
            )
        });
        if let Some((kappa, m_t)) = tangential {
            resolve(t_h * (m_t / (kappa * m_star)).sqrt());
        }
        // A live contact may be far stiffer than Hertz's sphere of the bounding radii (a face
        // on a face): its own stiffness's half-periods, normal and tangential, count too.
        // A contact of the network (see `substeps_with`) has its spring resolved there, with
        // the levers it has and the other contacts of its bodies.
        // A stiffness beyond the numbers (the force law overflowed) would ask for no
        // sub-step at all.
        if let Some(k_n) = live.map(|s| s.normal_stiffness).filter(|k| !k.is_finite()) {
            return Err(Error::NonFinite {
                what: "normal stiffness of a live contact",
                detail: format!("{k_n} N/m between {}", named((ca, cb))),
            });
        }
        if let Some(s) = live.filter(|s| s.normal_stiffness > 0.0) {
            let k_n = s.normal_stiffness;
            resolve(core::f64::consts::PI * (m_star / k_n).sqrt());
            let networked = in_network && s.frame.is_some();
            if let Some((kappa, m_t)) = tangential.filter(|_| !networked) {
                resolve(core::f64::consts::PI * (m_t / (kappa * k_n)).sqrt());
            }
        }
        Ok(())
    }

    /// The sub-steps of `dt` that `limits` ask for, as the policy allows: refused with
    /// [`Error::TimeStepTooLarge`] beyond the policy's sub-steps, or with
    /// [`Error::PrecisionTooLow`] where a sub-step moves the coarsest pair by too few spacings
    /// of its coordinates.
    pub(super) fn divide(&self, dt: Real, limits: &Limits) -> Result<usize> {
        let named = |(a, b): Pair| format!("colliders {a:?} and {b:?}");
        let substeps = match limits.worst {
            None => match self.policy {
                StepPolicy::Fixed { substeps } => substeps.max(1),
                StepPolicy::AutoSubstep { .. } => 1,
            },
            Some((recommended, contact_time, pair)) => {
                let needed = (dt / recommended).ceil().max(1.0) as usize;
                let (allowed, chosen) = match self.policy {
                    StepPolicy::Fixed { substeps } => (substeps.max(1), substeps.max(1)),
                    StepPolicy::AutoSubstep { max_substeps } => (max_substeps.max(1), needed),
                };
                if needed > allowed {
                    return Err(Error::TimeStepTooLarge {
                        dt,
                        recommended,
                        contact_time,
                        substeps_needed: needed,
                        pair: named(pair),
                    });
                }
                chosen.max(needed)
            }
        };
        let substep = dt / substeps as Real;
        if let Some((_, speed, largest, spacing, pair)) = limits.coarsest {
            if speed * substep < PRECISION_SPACINGS * spacing {
                return Err(Error::PrecisionTooLow {
                    pair: named(pair),
                    precision: boundary::PRECISION,
                    distance: largest,
                    substep,
                    indentation: speed * substep,
                    spacing,
                    required: PRECISION_SPACINGS,
                });
            }
        }
        Ok(substeps)
    }
}

/// What a step's pairs ask of its sub-steps.
#[derive(Default)]
pub(super) struct Limits {
    /// (largest sub-step, the contact time that sets it, the pair)
    pub(super) worst: Option<(Real, Real, Pair)>,
    /// The moving pair whose approach the coordinates resolve least: (approach speed over
    /// the coordinates' spacing, speed, largest coordinate, spacing, the pair).
    pub(super) coarsest: Option<(Real, Real, Real, Real, Pair)>,
}

impl Limits {
    /// A sub-step of at most `substep` (s) for `pair`, whose contact time is `time`.
    pub(super) fn resolve(&mut self, substep: Real, time: Real, pair: Pair) {
        if substep.is_finite() && substep > 0.0 && self.worst.is_none_or(|w| substep < w.0) {
            self.worst = Some((substep, time, pair));
        }
    }
}
