//! The one list of kernels: every ray–primitive test of the crate, named once.
//!
//! The vector runner ([`vectors`](crate#layout), feature `vectors`), the demo's sphere methods
//! (feature `demo`), the benchmarks, the firmware under `targets/`, the op-count report
//! ([`opcount::table`](crate::opcount::table)) and the study ([`study`](crate::study)) all walk
//! this list; adding a kernel means adding one row to the table at the end of this file (and
//! the kernel's own file).
//!
//! * A [`Kernel`] is one test of one primitive: a type implementing [`SphereKernel`],
//!   [`FocalKernel`] or [`TriangleKernel`] (some also [`PrecomputedKernel`]), the ray–plane
//!   test or one of
//!   the focal caches of planes and triangles. It carries its name (as the op-count report
//!   spells it), what it intersects ([`Prim`]), whether it needs unit directions, and the
//!   error model its documented limits follow ([`ErrorModel`]), and its source (the paper or
//!   lecture, short: [`Kernel::source`]).
//! * A [`Method`] is a name under which the checker runs kernels over the test vectors: one
//!   kernel per primitive it tests. Every method has one kernel except `focal`, whose sphere,
//!   plane and triangle caches run under one name (one digest per lane width).
//! * [`Kernel::visit`] turns the value into a type: a [`Visitor`] gets one generic call per
//!   family of kernels, with the kernel's type as a type parameter, so code written once for a
//!   family runs every kernel of it at full speed (no dynamic dispatch in the kernel).
//!
//! ```
//! use raylane_lab::registry::{Kernel, Method, Prim};
//!
//! assert_eq!(Kernel::from_name("watertight"), Some(Kernel::Watertight));
//! assert_eq!(Method::Focal.kernel(Prim::Triangle), Some(Kernel::TriangleFocal));
//! assert_eq!(Kernel::TriangleFocal.method(), Method::Focal);
//! assert!(Kernel::ALL.iter().all(|k| Kernel::from_name(k.name()) == Some(*k)));
//! ```

use raylane::sphere::SphereKernel;
use raylane::sphere::focal::FocalKernel;
use raylane::triangle::{PrecomputedKernel, TriangleKernel};

/// What a kernel intersects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Prim {
    /// Spheres.
    Sphere,
    /// Planes.
    Plane,
    /// Triangles.
    Triangle,
}

impl Prim {
    /// Every primitive.
    pub const ALL: [Prim; 3] = [Prim::Sphere, Prim::Plane, Prim::Triangle];

    /// Lower-case singular name (`sphere`), the keyword of a vector line.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Prim::Sphere => "sphere",
            Prim::Plane => "plane",
            Prim::Triangle => "triangle",
        }
    }

    /// Lower-case plural name (`spheres`).
    #[must_use]
    pub const fn plural(self) -> &'static str {
        match self {
            Prim::Sphere => "spheres",
            Prim::Plane => "planes",
            Prim::Triangle => "triangles",
        }
    }
}

/// How a kernel is called: which [`Visitor`] method [`Kernel::visit`] calls.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// A [`SphereKernel`] over spheres ([`Visitor::sphere`]).
    Sphere,
    /// A [`FocalKernel`] over sphere focal caches ([`Visitor::focal_sphere`]), built by
    /// [`FocalSphere::new`](raylane::sphere::FocalSphere::new) (`guarded`) or
    /// [`FocalSphere::unguarded`](raylane::sphere::FocalSphere::unguarded).
    FocalSphere {
        /// Which cache the kernel reads.
        guarded: bool,
    },
    /// The ray–plane test ([`Visitor::plane`]).
    Plane,
    /// The plane focal cache ([`Visitor::focal_plane`]).
    FocalPlane,
    /// A [`TriangleKernel`] over triangles ([`Visitor::triangle`]).
    Triangle,
    /// A [`TriangleKernel`] that is also a [`PrecomputedKernel`] ([`Visitor::precomputed`]).
    Precomputed,
    /// The triangle focal cache ([`Visitor::focal_triangle`]).
    FocalTriangle,
}

/// The error model a kernel's documented limits follow (what the vector runner's limits test,
/// in f64, before comparing a case against the kernel's result).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorModel {
    /// Exact decisions and `t` within the fixed tolerance on every case (the focal caches, the
    /// plane test, the watertight triangle test).
    Exact,
    /// The textbook quadratic's constant term `c² − r²`, rounded at the scale of `c²`: wrong
    /// near the rim of far spheres.
    Textbook,
    /// The robust forms (`f = o − C` and `|l|`): wrong only within a few ulps of `|f|` of the
    /// rim.
    RobustSphere,
    /// `t` as a triple product over the determinant: relative error growing with the aspect
    /// ratio on needles.
    Needle,
    /// A record computed once per triangle (plane, lines, transform) that carries the
    /// coordinates' magnitude into every test.
    Record,
}

/// One generic call per family of kernels: see [`Kernel::visit`]. Each method gets the kernel
/// (its metadata) and, where there is one, its type.
pub trait Visitor {
    /// What the visit returns.
    type Output;
    /// A sphere kernel `K` over spheres.
    fn sphere<K: SphereKernel>(self, k: Kernel) -> Self::Output;
    /// A focal kernel `K` over sphere focal caches; `guarded` says which cache it reads
    /// ([`FocalSphere::new`](raylane::sphere::FocalSphere::new) or
    /// [`FocalSphere::unguarded`](raylane::sphere::FocalSphere::unguarded)).
    fn focal_sphere<K: FocalKernel>(self, k: Kernel, guarded: bool) -> Self::Output;
    /// The ray–plane test over planes.
    fn plane(self, k: Kernel) -> Self::Output;
    /// The plane focal cache.
    fn focal_plane(self, k: Kernel) -> Self::Output;
    /// A triangle kernel `K` over triangles.
    fn triangle<K: TriangleKernel>(self, k: Kernel) -> Self::Output;
    /// A triangle kernel that can also run on stored records; by default the same as
    /// [`triangle`](Self::triangle) (which precomputes on the fly).
    fn precomputed<K: TriangleKernel + PrecomputedKernel>(self, k: Kernel) -> Self::Output
    where
        Self: Sized,
    {
        self.triangle::<K>(k)
    }
    /// The triangle focal cache.
    fn focal_triangle(self, k: Kernel) -> Self::Output;
}

/// The [`Family`] and [`Prim`] of a row's call.
macro_rules! family {
    (sphere($t:ty)) => {
        (Family::Sphere, Prim::Sphere)
    };
    (focal_sphere($t:ty, $g:literal)) => {
        (Family::FocalSphere { guarded: $g }, Prim::Sphere)
    };
    (plane) => {
        (Family::Plane, Prim::Plane)
    };
    (focal_plane) => {
        (Family::FocalPlane, Prim::Plane)
    };
    (triangle($t:ty)) => {
        (Family::Triangle, Prim::Triangle)
    };
    (precomputed($t:ty)) => {
        (Family::Precomputed, Prim::Triangle)
    };
    (focal_triangle) => {
        (Family::FocalTriangle, Prim::Triangle)
    };
}

/// The [`Visitor`] call of a row.
macro_rules! visit {
    ($v:ident, $k:ident, sphere($t:ty)) => {
        $v.sphere::<$t>($k)
    };
    ($v:ident, $k:ident, focal_sphere($t:ty, $g:literal)) => {
        $v.focal_sphere::<$t>($k, $g)
    };
    ($v:ident, $k:ident, plane) => {
        $v.plane($k)
    };
    ($v:ident, $k:ident, focal_plane) => {
        $v.focal_plane($k)
    };
    ($v:ident, $k:ident, triangle($t:ty)) => {
        $v.triangle::<$t>($k)
    };
    ($v:ident, $k:ident, precomputed($t:ty)) => {
        $v.precomputed::<$t>($k)
    };
    ($v:ident, $k:ident, focal_triangle) => {
        $v.focal_triangle($k)
    };
}

/// Generates [`Method`] and [`Kernel`] from the table below.
macro_rules! registry {
    ($(
        $(#[doc = $mdoc:literal])*
        $method:ident $mname:literal {
            $(
                $(#[doc = $kdoc:literal])*
                $kernel:ident $kname:literal, unit: $unit:literal, error: $err:ident,
                    source: $src:literal, $fam:ident $(($($arg:tt)*))?;
            )+
        }
    )+) => {
        /// A name under which the checker runs kernels over the test vectors (one kernel per
        /// primitive it tests): see the [module docs](self).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Method {
            $( $(#[doc = $mdoc])* $method, )+
        }

        /// One ray–primitive test: see the [module docs](self).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Kernel {
            $( $( $(#[doc = $kdoc])* $kernel, )+ )+
        }

        impl Method {
            /// Every method, in report order.
            pub const ALL: [Method; [$(stringify!($method)),+].len()] = [$(Method::$method),+];

            /// The checker's name.
            #[must_use]
            pub const fn name(self) -> &'static str {
                match self {
                    $( Method::$method => $mname, )+
                }
            }

            /// The kernels run under this name, one per primitive.
            #[must_use]
            pub const fn kernels(self) -> &'static [Kernel] {
                match self {
                    $( Method::$method => &[$(Kernel::$kernel),+], )+
                }
            }
        }

        impl Kernel {
            /// Every kernel, in the order of [`Method::ALL`] (each method's kernels together).
            pub const ALL: [Kernel; [$($(stringify!($kernel)),+),+].len()] =
                [$($(Kernel::$kernel),+),+];

            /// The name, as the op-count report and the benchmarks spell it.
            #[must_use]
            pub const fn name(self) -> &'static str {
                match self {
                    $( $( Kernel::$kernel => $kname, )+ )+
                }
            }

            /// Where the test comes from, short (the paper, the lecture or raylane), as the
            /// op-count study's table ([`study`](crate::study)) prints it.
            #[must_use]
            pub const fn source(self) -> &'static str {
                match self {
                    $( $( Kernel::$kernel => $src, )+ )+
                }
            }

            /// The checker's method that runs this kernel.
            #[must_use]
            pub const fn method(self) -> Method {
                match self {
                    $( $( Kernel::$kernel => Method::$method, )+ )+
                }
            }

            /// How it is called.
            #[must_use]
            pub const fn family(self) -> Family {
                match self {
                    $( $( Kernel::$kernel => family!($fam $(($($arg)*))?).0, )+ )+
                }
            }

            /// What it intersects.
            #[must_use]
            pub const fn prim(self) -> Prim {
                match self {
                    $( $( Kernel::$kernel => family!($fam $(($($arg)*))?).1, )+ )+
                }
            }

            /// True when the kernel needs unit-length ray directions (it normalises nothing:
            /// other directions give wrong roots).
            #[must_use]
            pub const fn needs_unit(self) -> bool {
                match self {
                    $( $( Kernel::$kernel => $unit, )+ )+
                }
            }

            /// The error model of its documented limits.
            #[must_use]
            pub const fn error_model(self) -> ErrorModel {
                match self {
                    $( $( Kernel::$kernel => ErrorModel::$err, )+ )+
                }
            }

            /// Calls the visitor's method for this kernel's family, with its type (inline on
            /// x86-64, so that it runs at the level its caller entered: `raylane::simd`).
            #[cfg_attr(target_arch = "x86_64", inline(always))]
            #[cfg_attr(not(target_arch = "x86_64"), inline)]
            pub fn visit<V: Visitor>(self, v: V) -> V::Output {
                match self {
                    $( $( Kernel::$kernel => {
                        let k = self;
                        visit!(v, k, $fam $(($($arg)*))?)
                    } )+ )+
                }
            }
        }
    };
}

impl Method {
    /// The method called `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Its kernel for primitive `p`, if it tests that primitive.
    #[must_use]
    pub fn kernel(self, p: Prim) -> Option<Kernel> {
        self.kernels().iter().copied().find(|k| k.prim() == p)
    }

    /// True when it tests primitive `p`.
    #[must_use]
    pub fn applies(self, p: Prim) -> bool {
        self.kernel(p).is_some()
    }
}

impl Kernel {
    /// The kernel called `name`.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Kernel> {
        Kernel::ALL.into_iter().find(|k| k.name() == name)
    }

    /// The kernels of primitive `p`, in [`Kernel::ALL`]'s order.
    pub fn of(p: Prim) -> impl Iterator<Item = Kernel> {
        Kernel::ALL.into_iter().filter(move |k| k.prim() == p)
    }

    /// True for the focal caches (rays from the cache's eye only).
    #[must_use]
    pub const fn is_focal(self) -> bool {
        matches!(
            self.family(),
            Family::FocalSphere { .. } | Family::FocalPlane | Family::FocalTriangle
        )
    }
}

// The table: one row per kernel, grouped by the checker's method. Columns: the kernel's enum
// variant and name, whether it needs unit directions, its error model, its source (short, as
// the study's table prints it: `focal-unguarded`'s "the same" is the guarded `focal`, the row
// above it there) and its call (family and type). Adding a kernel is adding a row here. Each
// row's docs quote its pinned miss and hit counts per lane (`opcount::table`, on the lectures'
// worked examples; the precomputed methods precompute on the fly there) as `ops` markers,
// which `tests/suite/docs/doc_op_counts.rs` checks against the table.
registry! {
    /// [`Quadratic`](raylane::sphere::Quadratic): the general quadratic.
    Quadratic "quadratic" {
        /// [`sphere::Quadratic`](raylane::sphere::Quadratic).
        ///
        /// Per lane: `ops quadratic/miss: 12 mul, 11 add, 1 cmp`;
        /// `ops quadratic/hit: 12 mul, 13 add, 2 div, 1 sqrt, 10 cmp`.
        Quadratic "quadratic", unit: false, error: Textbook,
            source: "the quadratic (lecture 004)", sphere(raylane::sphere::Quadratic);
    }
    /// [`QuadraticUnit`](raylane::sphere::QuadraticUnit): the quadratic with `a = 1`.
    QuadraticUnit "quadratic-unit" {
        /// [`sphere::QuadraticUnit`](raylane::sphere::QuadraticUnit).
        ///
        /// Per lane: `ops quadratic-unit/miss: 8 mul, 9 add, 1 cmp`;
        /// `ops quadratic-unit/hit: 8 mul, 11 add, 1 sqrt, 8 cmp`.
        QuadraticUnit "quadratic-unit", unit: true, error: Textbook,
            source: "lecture 000, unit d", sphere(raylane::sphere::QuadraticUnit);
    }
    /// [`Geometric`](raylane::sphere::Geometric): the lecture's geometric test.
    Geometric "geometric" {
        /// [`sphere::Geometric`](raylane::sphere::Geometric).
        ///
        /// Per lane: `ops geometric/miss: 8 mul, 8 add, 1 cmp`;
        /// `ops geometric/hit: 8 mul, 11 add, 1 sqrt, 8 cmp`.
        Geometric "geometric", unit: true, error: Textbook,
            source: "Glassner's geometric test, unit d", sphere(raylane::sphere::Geometric);
    }
    /// [`Robust`](raylane::sphere::Robust): Ray Tracing Gems ch. 7.
    Robust "robust" {
        /// [`sphere::Robust`](raylane::sphere::Robust).
        ///
        /// Per lane: `ops robust/miss: 14 mul, 13 add, 1 div, 1 cmp`;
        /// `ops robust/hit: 17 mul, 17 add, 3 div, 1 sqrt, 12 cmp`.
        Robust "robust", unit: false, error: RobustSphere,
            source: "Ray Tracing Gems ch. 7", sphere(raylane::sphere::Robust);
    }
    /// The focal caches of spheres (guarded), planes and triangles; per vector case the eye is
    /// the ray origin.
    Focal "focal" {
        /// [`sphere::focal::Focal`](raylane::sphere::focal::Focal) over guarded caches.
        ///
        /// Per lane: `ops focal/miss: 4 mul, 2 add, 1 cmp`;
        /// `ops focal/hit: 10 mul, 10 add, 1 sqrt, 9 cmp`.
        Focal "focal", unit: true, error: Exact,
            source: "raylane: rays from one eye, unit d",
            focal_sphere(raylane::sphere::focal::Focal, true);
        /// [`FocalPlane`](raylane::plane::FocalPlane) caches.
        ///
        /// Per lane: `ops plane-focal/miss: 3 mul, 2 add, 1 div, 2 cmp`;
        /// `ops plane-focal/hit: 3 mul, 2 add, 1 div, 2 cmp`.
        PlaneFocal "plane-focal", unit: false, error: Exact,
            source: "raylane: rays from one eye", focal_plane;
        /// [`FocalTriangle`](raylane::triangle::FocalTriangle) caches.
        ///
        /// Per lane: `ops triangle-focal/miss: 9 mul, 6 add, 6 cmp`;
        /// `ops triangle-focal/hit: 13 mul, 10 add, 1 div, 15 cmp`.
        TriangleFocal "triangle-focal", unit: false, error: Exact,
            source: "raylane: rays from one eye", focal_triangle;
    }
    /// [`FocalUnguarded`](raylane::sphere::focal::FocalUnguarded): the lecture's unguarded focal
    /// test.
    FocalUnguarded "focal-unguarded" {
        /// [`sphere::focal::FocalUnguarded`](raylane::sphere::focal::FocalUnguarded) over
        /// unguarded caches.
        ///
        /// Per lane: `ops focal-unguarded/miss: 4 mul, 2 add, 1 cmp`;
        /// `ops focal-unguarded/hit: 4 mul, 5 add, 1 sqrt, 5 cmp`.
        FocalUnguarded "focal-unguarded", unit: true, error: Textbook,
            source: "the same without the precision guard",
            focal_sphere(raylane::sphere::focal::FocalUnguarded, false);
    }
    /// The ray–plane test.
    Plane "plane" {
        /// [`plane::intersect_lanes`](raylane::plane::intersect_lanes).
        ///
        /// Per lane: `ops plane/miss: 6 mul, 7 add, 1 div, 2 cmp`;
        /// `ops plane/hit: 6 mul, 7 add, 1 div, 2 cmp`.
        Plane "plane", unit: false, error: Exact,
            source: "lecture 002", plane;
    }
    /// [`Cramer`](raylane::triangle::Cramer): lecture 002.
    Cramer "cramer" {
        /// [`triangle::Cramer`](raylane::triangle::Cramer).
        ///
        /// Per lane: `ops cramer/miss: 21 mul, 22 add, 2 div, 5 cmp`;
        /// `ops cramer/hit: 30 mul, 27 add, 3 div, 7 cmp`.
        Cramer "cramer", unit: false, error: Needle,
            source: "lecture 002 (Cramer's rule)", triangle(raylane::triangle::Cramer);
    }
    /// [`Moller`](raylane::triangle::Moller): Möller–Trumbore, division deferred.
    Moller "moller" {
        /// [`triangle::Moller`](raylane::triangle::Moller).
        ///
        /// Per lane: `ops moller/miss: 21 mul, 22 add, 5 cmp`;
        /// `ops moller/hit: 25 mul, 24 add, 1 div, 12 cmp`.
        Moller "moller", unit: false, error: Needle,
            source: "Möller–Trumbore 1997, division deferred", triangle(raylane::triangle::Moller);
    }
    /// [`Watertight`](raylane::triangle::Watertight): Woop, Benthin, Wald 2013.
    Watertight "watertight" {
        /// [`triangle::Watertight`](raylane::triangle::Watertight).
        ///
        /// Per lane: `ops watertight/miss: 12 mul, 18 add, 6 cmp`;
        /// `ops watertight/hit: 19 mul, 22 add, 1 div, 15 cmp`.
        Watertight "watertight", unit: false, error: Exact,
            source: "Woop–Benthin–Wald 2013", triangle(raylane::triangle::Watertight);
    }
    /// [`Pbrt`](raylane::sphere::Pbrt): pbrt-v4's sphere test, without intervals.
    Pbrt "pbrt" {
        /// [`sphere::Pbrt`](raylane::sphere::Pbrt).
        ///
        /// Per lane: `ops pbrt/miss: 21 mul, 17 add, 1 div, 1 sqrt, 1 cmp`;
        /// `ops pbrt/hit: 22 mul, 18 add, 3 div, 2 sqrt, 7 cmp`.
        Pbrt "pbrt", unit: false, error: RobustSphere,
            source: "pbrt-v4, intervals aside", sphere(raylane::sphere::Pbrt);
    }
    /// [`EmbreeSphere`](raylane::sphere::EmbreeSphere): Embree's sphere test.
    EmbreeSphere "embree" {
        /// [`sphere::EmbreeSphere`](raylane::sphere::EmbreeSphere).
        ///
        /// Per lane: `ops embree/miss: 14 mul, 12 add, 1 div, 1 cmp`;
        /// `ops embree/hit: 15 mul, 15 add, 1 div, 1 sqrt, 5 cmp`.
        EmbreeSphere "embree", unit: false, error: RobustSphere,
            source: "Embree sphere_intersector", sphere(raylane::sphere::EmbreeSphere);
    }
    /// [`Badouel`](raylane::triangle::Badouel): Badouel 1990, plane then a 2-D test.
    Badouel "badouel" {
        /// [`triangle::Badouel`](raylane::triangle::Badouel).
        ///
        /// Per lane: `ops badouel/miss: 23 mul, 28 add, 3 div, 9 cmp`;
        /// `ops badouel/hit: 23 mul, 28 add, 3 div, 9 cmp`.
        Badouel "badouel", unit: false, error: Record,
            source: "Badouel 1990", precomputed(raylane::triangle::Badouel);
    }
    /// [`Plucker`](raylane::triangle::Plucker): Plücker edge tests (Segura–Feito 1998, as in
    /// Embree).
    Plucker "plucker" {
        /// [`triangle::Plucker`](raylane::triangle::Plucker).
        ///
        /// Per lane: `ops plucker/miss: 28 mul, 44 add, 6 cmp`;
        /// `ops plucker/hit: 41 mul, 53 add, 1 div, 20 cmp`.
        Plucker "plucker", unit: false, error: Needle,
            source: "Segura–Feito 1998 (Embree's Plücker)", triangle(raylane::triangle::Plucker);
    }
    /// [`Wald`](raylane::triangle::Wald): Wald 2004, precomputed projection.
    Wald "wald" {
        /// [`triangle::Wald`](raylane::triangle::Wald).
        ///
        /// Per lane: `ops wald/miss: 31 mul, 25 add, 2 div, 9 cmp`;
        /// `ops wald/hit: 31 mul, 25 add, 2 div, 9 cmp`.
        Wald "wald", unit: false, error: Record,
            source: "Wald 2004", precomputed(raylane::triangle::Wald);
    }
    /// [`HavelHerout`](raylane::triangle::HavelHerout): Havel–Herout 2010, precomputed planes.
    HavelHerout "havel-herout" {
        /// [`triangle::HavelHerout`](raylane::triangle::HavelHerout).
        ///
        /// Per lane: `ops havel-herout/miss: 56 mul, 39 add, 1 div, 5 cmp`;
        /// `ops havel-herout/hit: 57 mul, 39 add, 2 div, 12 cmp`.
        HavelHerout "havel-herout", unit: false, error: Record,
            source: "Havel–Herout 2010", precomputed(raylane::triangle::HavelHerout);
    }
    /// [`KenslerShirley`](raylane::triangle::KenslerShirley): Kensler–Shirley 2006.
    KenslerShirley "kensler-shirley" {
        /// [`triangle::KenslerShirley`](raylane::triangle::KenslerShirley).
        ///
        /// Per lane: `ops kensler-shirley/miss: 23 mul, 22 add, 1 div, 3 cmp`;
        /// `ops kensler-shirley/hit: 27 mul, 24 add, 1 div, 5 cmp`.
        KenslerShirley "kensler-shirley", unit: false, error: Needle,
            source: "Kensler–Shirley 2006", triangle(raylane::triangle::KenslerShirley);
    }
    /// [`BaldwinWeber`](raylane::triangle::BaldwinWeber): Baldwin–Weber 2016, precomputed affine
    /// transform.
    BaldwinWeber "baldwin-weber" {
        /// [`triangle::BaldwinWeber`](raylane::triangle::BaldwinWeber).
        ///
        /// Per lane: `ops baldwin-weber/miss: 37 mul, 30 add, 2 div, 8 cmp`;
        /// `ops baldwin-weber/hit: 37 mul, 30 add, 2 div, 8 cmp`.
        BaldwinWeber "baldwin-weber", unit: false, error: Record,
            source: "Baldwin–Weber 2016", precomputed(raylane::triangle::BaldwinWeber);
    }
}

/// The names agree with the kernel types' own `NAME`s, and the unit-direction flags with
/// [`SphereKernel::UNIT_DIRECTIONS`].
#[cfg(test)]
mod tests {
    use super::*;

    struct Names;
    impl Visitor for Names {
        type Output = (&'static str, Option<bool>);
        fn sphere<K: SphereKernel>(self, _: Kernel) -> Self::Output {
            (K::NAME, Some(K::UNIT_DIRECTIONS))
        }
        fn focal_sphere<K: FocalKernel>(self, _: Kernel, _: bool) -> Self::Output {
            (K::NAME, Some(true))
        }
        fn plane(self, k: Kernel) -> Self::Output {
            (k.name(), Some(false))
        }
        fn focal_plane(self, k: Kernel) -> Self::Output {
            (k.name(), Some(false))
        }
        fn triangle<K: TriangleKernel>(self, _: Kernel) -> Self::Output {
            (K::NAME, Some(false))
        }
        fn focal_triangle(self, k: Kernel) -> Self::Output {
            (k.name(), Some(false))
        }
    }

    #[test]
    fn names_and_flags_agree_with_the_types() {
        for k in Kernel::ALL {
            let (name, unit) = k.visit(Names);
            assert_eq!(name, k.name());
            assert_eq!(unit, Some(k.needs_unit()), "{}", k.name());
            assert_eq!(k.method().kernel(k.prim()), Some(k));
        }
        for m in Method::ALL {
            assert_eq!(Method::from_name(m.name()), Some(m));
            assert!(m.kernels().iter().all(|k| k.method() == m));
        }
    }
}
