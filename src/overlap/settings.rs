//! What the overlap computation is asked for: the integration mode, the grid's resolution, the
//! contact enlargement and the opt-in exact forms.

use crate::error::{check_non_negative, check_range, Result};
use crate::math::Real;

/// How the overlap region is integrated on its grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
pub enum IntegrationMode {
    /// Node counting, as in Marquardt et al. (first order in `N_c`).
    Count,
    /// Piecewise-linear sub-cell integration (second order in `N_c`): exact surface crossings
    /// on the grid's edges, and the bodies' tangent planes in cells an edge or a corner of a
    /// body passes through, which keep flat-faced bodies' edges sharp. Relies on exact SDFs
    /// and their gradients (as [`Sdf`](crate::Sdf) requires).
    Subcell,
}

impl IntegrationMode {
    /// `"count"` or `"subcell"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Count => "count",
            Self::Subcell => "subcell",
        }
    }
}

/// Resolution and mode of the overlap integration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "checkpoint", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "checkpoint", serde(try_from = "SettingsFields"))]
pub struct OverlapSettings {
    pub(super) n_c: usize,
    pub(super) mode: IntegrationMode,
    pub(super) enlargement: [Real; 2],
    pub(super) closed_form_spheres: bool,
    pub(super) exact_polyhedra: bool,
    pub(super) polyhedra_on_grid: bool,
    pub(super) facet_bulge: bool,
}

impl OverlapSettings {
    /// `n_c >= 1` grid cells per direction on the overlap's box.
    pub fn new(n_c: usize, mode: IntegrationMode) -> Result<Self> {
        check_range("n_c", n_c as Real, 1.0..=1024.0, "integer 1 <= N_c <= 1024")?;
        Ok(Self {
            n_c,
            mode,
            enlargement: [0.0; 2],
            closed_form_spheres: false,
            exact_polyhedra: false,
            polyhedra_on_grid: false,
            facet_bulge: true,
        })
    }

    /// Sphere–sphere and sphere–half-space pairs get their overlap in closed form (a lens of
    /// two spherical caps, one cap on a plane) instead of on the grid: what the grid integration
    /// converges to as `N_c` grows, in a few operations instead of a grid integration. Every
    /// other pair — and a configuration the closed form does not
    /// cover, such as one sphere inside the other — is integrated on the grid as before. Off
    /// by default: the grid is the model, and the validations measure it.
    pub fn with_closed_form_spheres(mut self, on: bool) -> Self {
        self.closed_form_spheres = on;
        self
    }

    /// Whether sphere pairs are computed in closed form.
    pub fn closed_form_spheres(&self) -> bool {
        self.closed_form_spheres
    }

    /// Pairs of bodies bounded by planes — cuboids, convex polyhedra, one of them possibly a
    /// half-space — get their overlap exactly: the intersection polyhedron of both bodies' face
    /// half-spaces, its volume, centroid, facet area vectors and chord in closed form, at a
    /// fraction of a grid integration's cost. It is
    /// what the grid integration converges to as `N_c` grows, except that an enlargement moves
    /// the faces out (sharp edges) where the grid's `d <= ε` rounds edges and corners. Every
    /// other pair (a sphere, a cylinder, a rounded or custom body) is integrated on the grid as
    /// before. Without enlargement in sub-cell mode this is what the grid computes anyway
    /// (see [`with_polyhedra_on_grid`](Self::with_polyhedra_on_grid)), and such pairs take the
    /// exact form whatever this setting; it decides for enlarged pairs and in counting mode.
    /// Off by default: the grid is the model, and the validations measure it.
    pub fn with_exact_polyhedra(mut self, on: bool) -> Self {
        self.exact_polyhedra = on;
        self
    }

    /// Whether pairs of planar bodies are computed exactly.
    pub fn exact_polyhedra(&self) -> bool {
        self.exact_polyhedra
    }

    /// In sub-cell mode, a pair of bodies bounded by planes and not enlarged is integrated on
    /// the grid, its cells clipped by the bodies' faces (`true`), instead of by clipping the
    /// whole overlap polyhedron once (`false`, the default). The grid's result then equals the
    /// clipping's to round-off, at several times its cost: this is for checking the grid's
    /// face clipping (which mixed pairs, a polyhedron and a curved body, rely on) against it.
    pub fn with_polyhedra_on_grid(mut self, on: bool) -> Self {
        self.polyhedra_on_grid = on;
        self
    }

    /// Whether non-enlarged polyhedral pairs are integrated on the grid in sub-cell mode.
    pub fn polyhedra_on_grid(&self) -> bool {
        self.polyhedra_on_grid
    }

    /// Sub-cell integration adds, for a body smooth and curved everywhere (a ball, a capsule),
    /// the layer between each of its interpolated facets and its surface, and completes the
    /// surface area at the rims it shares with the other body (`true`, the default). The
    /// facets' corners lie on the surface and the facets inside the convex body, so
    /// interpolation leaves out a layer quadratic over each facet: with it the volume of such a
    /// pair is third order in the grid's spacing instead of second — a sphere on a plane or on
    /// a sphere at `N_c` = 4 within a few 1e-4 of its converged value, as close as `N_c` = 32
    /// comes without it — for about a quarter more work per evaluation of a sphere pair at the
    /// same `N_c`. Bodies with edges or flat faces (cuboids, hulls, cylinders, cones, enlarged
    /// polyhedra) and half-spaces carry no layer (their area at a rim shared with a ball or a
    /// capsule is completed all the same). `false` integrates the interpolated facets alone
    /// (second order, as before the layer; `hertz_validation -- --no-facet-bulge`). The f32
    /// drop-in's agreement with the f64 one is tested with it and without, over many bounces
    /// against the f64 build rounded to f32 (`tests/rapier_f32.rs`).
    pub fn with_facet_bulge(mut self, on: bool) -> Self {
        self.facet_bulge = on;
        self
    }

    /// Whether smooth bodies' facets carry the layer to their surface in sub-cell mode.
    pub fn facet_bulge(&self) -> bool {
        self.facet_bulge
    }

    /// Contact enlargement `ε_A, ε_B >= 0` (m): a node is inside when `d_A <= ε_A` and `d_B <= ε_B`.
    pub fn with_enlargement(mut self, eps_a: Real, eps_b: Real) -> Result<Self> {
        self.enlargement = [
            check_non_negative("enlargement_a", eps_a)?,
            check_non_negative("enlargement_b", eps_b)?,
        ];
        Ok(self)
    }

    /// Grid cells per direction.
    pub fn n_c(&self) -> usize {
        self.n_c
    }

    /// Integration mode.
    pub fn mode(&self) -> IntegrationMode {
        self.mode
    }

    /// Contact enlargement of A and B (m).
    pub fn enlargement(&self) -> [Real; 2] {
        self.enlargement
    }
}

deserialize_checked!(OverlapSettings via SettingsFields { n_c: usize, mode: IntegrationMode, enlargement: [Real; 2], closed_form_spheres: bool, exact_polyhedra: bool, #[serde(default)] polyhedra_on_grid: bool, #[serde(default)] facet_bulge: bool }
    => |f| OverlapSettings::new(f.n_c, f.mode)
        .and_then(|s| s.with_enlargement(f.enlargement[0], f.enlargement[1]))
        .map(|s| s.with_closed_form_spheres(f.closed_form_spheres).with_exact_polyhedra(f.exact_polyhedra).with_polyhedra_on_grid(f.polyhedra_on_grid).with_facet_bulge(f.facet_bulge)));
