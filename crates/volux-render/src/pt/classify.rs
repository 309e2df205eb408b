//! Per-tetrahedron classification of Projected Tetrahedra: four exact orientation tests, the
//! ternary truth table and the thick vertex.
//!
//! # The four tests (seed `000` figure 4.3, seed `002` figure 4)
//!
//! Write `O(i, j, k) = (v_j - v_i) × (v_k - v_i)` (the `z` of the cross product, twice the
//! signed area of the projected triangle `v_i v_j v_k`, positive when counter-clockwise in a
//! y-up frame). With `vec_1 = v_1 - v_0`, `vec_2 = v_2 - v_0`, `vec_3 = v_3 - v_0`,
//! `vec_4 = v_1 - v_2`, `vec_5 = v_1 - v_3`, the seeds' tests are
//!
//! | test | seed | here |
//! |---|---|---|
//! | `test_1` | `sign((vec_1 × vec_2).z) + 1` | `sign O(0,1,2) + 1` |
//! | `test_2` | `sign((vec_1 × vec_3).z) + 1` | `sign O(0,1,3) + 1` |
//! | `test_3` | `sign((vec_2 × vec_3).z) + 1` | `sign O(0,2,3) + 1` |
//! | `test_4` | `sign((vec_4 × vec_5).z) + 1` | `sign O(1,2,3) + 1` |
//!
//! (`(v_1 - v_2) × (v_1 - v_3) = (v_2 - v_1) × (v_3 - v_1)`), i.e. the orientations of the four
//! faces of the tetrahedron in projection, and the table index is
//! `id = 27 test_1 + 9 test_2 + 3 test_3 + test_4` (seed `000` eq. 4.1), `0..=80`. Every sign
//! is computed by [`orient2d`], which is exact, so the code is the code of the exact
//! projected positions: no tolerance, no inconsistent combination.
//!
//! # Deriving the table: the affine dependency of four points
//!
//! For any four points of the plane
//! `λ = (λ_0, λ_1, λ_2, λ_3) = (O(1,2,3), -O(0,2,3), O(0,1,3), -O(0,1,2))`
//! satisfies `Σ λ_m = 0` and `Σ λ_m v_m = 0` (the cofactors of the 3×4 matrix whose columns
//! are `(1, x_m, y_m)`): it is the affine dependency of the four points, and its signs are
//! the four tests (up to the fixed signs above). Splitting the vertices by the sign of `λ_m`
//! gives their Radon partition, which *is* the PT class:
//!
//! | signs of `λ` | geometry | class | triangles | thick vertex |
//! |---|---|---|---|---|
//! | one against three, none zero | the lone vertex is strictly inside the triangle of the other three | 1 | 3 | that vertex |
//! | two against two, none zero | the two segments cross | 2 | 4 | the crossing of the two edges |
//! | one against two, one zero | the lone vertex is strictly inside the segment of the pair; the zero one is off that line | 3 | 2 | the vertex on the edge |
//! | one against one, two zero | the two vertices coincide | 4 | 1 | the coincident pair |
//! | all zero | the four projected vertices are collinear | degenerate | 0 | none (discarded) |
//! | all non-zero ones of one sign | impossible, since `Σ λ_m = 0` | inconsistent | 0 | none |
//!
//! Counting sign vectors: class 1 has 4 lone vertices × 2 signs = 8 codes, class 2 has
//! `C(4,2) = 6`, together the **14** cases of Wylie et al.; class 3 has 4 zero positions × 6
//! mixed sign patterns of the other three = **24**; class 4 has `C(4,2)` zero pairs × 2 = **12**.
//! That is the seeds' **50** valid cases exactly (`000` §4.1: "Em cima dos 14 casos do Wylie
//! et. al., foram adicionados 24 casos da classe três e 12 casos da classe quatro. No total,
//! 50 casos"; `002` §4.1). The other 31 entries are the collinear code `1111` (`id` 40) and 30
//! inconsistent codes: 2 with no zero test, 8 with one, 12 with two and **all 8 with exactly
//! three zero tests**.
//!
//! A precise difference with the seeds' wording: they say that "three or four tests yielding 1
//! indicate degenerate tetrahedra which can be discarded" (`002` §4.1) and describe
//! `test_1234 = 0111` (`id` 13) as four collinear vertices (`000` §4.1). With exactly evaluated
//! signs three zero tests cannot occur: three degenerate faces force the fourth to be
//! degenerate through `Σ λ_m = 0`, so such a code can only come from rounding. The table marks
//! these entries [`DegenerateReason::Inconsistent`] rather than collinear; since both are
//! discarded, the rendering is the same, and [`classify`] never returns an inconsistent code.
//! The seeds' stated counts (14 + 24 + 12 = 50) agree with the derivation.
//!
//! The table is built by a `const fn` from this sign analysis ([`TERNARY_TABLE`]); the tests
//! check all 81 entries against a brute-force geometric classification (point in triangle,
//! segment crossing, coincidence, point on segment) of exhaustive small-grid configurations,
//! hand-made ones and 10^5 random ones.
//!
//! # Fan layout
//!
//! The fan indexes a five-point array `[v_0, v_1, v_2, v_3, v_t]` ([`Classification::points`]):
//! the four projected vertices and the thick vertex at index 4, as in the seeds' vertex arrays
//! (`000` figure 4.6, `002` figure 6). [`Fan::indices`] lists `cnt` indices (3 to 6) drawn as
//! a triangle fan: the first is always 4, and triangle `i` is
//! `(4, indices[i + 1], indices[i + 2])`, so there are `cnt - 2` triangles. The rim runs
//! counter-clockwise (positive [`orient2d`]) around the convex hull of the projection:
//!
//! | class | fan | triangles |
//! |---|---|---|
//! | 1, `v_k` inside `v_i v_j v_l` | `4 i j l i` | 3 |
//! | 2, `v_a v_b` crosses `v_c v_d` | `4 a c b d a` | 4 |
//! | 3, `v_m` on `v_e v_f`, apex `v_w` | `4 f w e` | 2 |
//! | 4, `v_p = v_q`, others `v_k v_l` | `4 k l` | 1 |
//!
//! The thick vertex takes the position of `v_k`, of the crossing point, of `v_m`, of `v_p`
//! respectively. The triangles are pairwise interior-disjoint and their union is the convex
//! hull of the projection.
//!
//! [`TableEntry::order`] is the seeds' `RGBA` texel (table 4.1 of `000`): the vertex order
//! `o` in which "the thick vertex is found by intersecting `v_0 - v_2` and `v_1 - v_3`"
//! (`000` §4.1, fifth step). The table reproduces every row that the thesis prints (`id` 0,
//! 1, 2, 3, 4 and 80).
use glam::DVec2;

pub use crate::geometry::{orient2d, Sign};

// -------------------------------------------------------------------------------------------
// The ternary truth table
// -------------------------------------------------------------------------------------------

/// Number of entries of the ternary truth table: `3^4`.
pub const TABLE_SIZE: usize = 81;

/// The class of a projected tetrahedron (seed `000` figure 3.1, seed `002` figure 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProjectionClass {
    /// Class 1: one projected vertex strictly inside the triangle of the other three; 3
    /// triangles.
    Class1,
    /// Class 2: the projection is a convex quadrilateral whose diagonals are two crossing
    /// edges of the tetrahedron; 4 triangles.
    Class2,
    /// Class 3: one projected vertex strictly inside the opposite projected edge; 2
    /// triangles.
    Class3,
    /// Class 4: two projected vertices coincide; 1 triangle.
    Class4,
    /// Nothing to draw; the reason says why.
    Degenerate(DegenerateReason),
}

impl ProjectionClass {
    /// The seeds' class number, 1 to 4; `None` when degenerate.
    pub const fn number(self) -> Option<u8> {
        match self {
            ProjectionClass::Class1 => Some(1),
            ProjectionClass::Class2 => Some(2),
            ProjectionClass::Class3 => Some(3),
            ProjectionClass::Class4 => Some(4),
            ProjectionClass::Degenerate(_) => None,
        }
    }

    /// Number of fan triangles: 3, 4, 2, 1 for classes 1 to 4, 0 when degenerate.
    pub const fn triangle_count(self) -> usize {
        match self {
            ProjectionClass::Class1 => 3,
            ProjectionClass::Class2 => 4,
            ProjectionClass::Class3 => 2,
            ProjectionClass::Class4 => 1,
            ProjectionClass::Degenerate(_) => 0,
        }
    }

    /// Whether the projection is discarded.
    pub const fn is_degenerate(self) -> bool {
        matches!(self, ProjectionClass::Degenerate(_))
    }
}

/// Why a projection is discarded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DegenerateReason {
    /// All four tests are zero: the four projected vertices are collinear, the projection has
    /// no area (a flat tetrahedron, or one seen edge-on). Table entry `id` 40 (`1111`).
    Collinear,
    /// A sign combination that exactly evaluated tests cannot produce (every non-zero `λ` of
    /// one sign, see the module documentation), including every code with exactly three
    /// zero tests. Only in the table; [`classify`] never returns it.
    Inconsistent,
    /// A coordinate is NaN or infinite.
    NonFinite,
}

/// Which vertices make up the thick vertex, for one table entry. Vertex indices are `0..4`;
/// lists of vertices are sorted ascending (crossing edges: the one holding vertex 0 first).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ThickTopology {
    /// Degenerate entry: no thick vertex.
    None,
    /// Class 1: `vertex` projects strictly inside the triangle `face`.
    Interior {
        /// The interior projected vertex: the thick vertex.
        vertex: u8,
        /// The other three vertices, whose face the ray leaves (or enters) through.
        face: [u8; 3],
    },
    /// Class 2: the two edges cross; the thick vertex is their intersection.
    Crossing {
        /// The two crossing edges (opposite edges of the tetrahedron).
        edges: [[u8; 2]; 2],
    },
    /// Class 3: `vertex` projects strictly inside the projection of `edge`.
    OnEdge {
        /// The projected vertex on the edge: the thick vertex.
        vertex: u8,
        /// The edge it lies on.
        edge: [u8; 2],
        /// The fourth vertex, off the line.
        apex: u8,
    },
    /// Class 4: the two vertices project to the same point, the thick vertex.
    Coincident {
        /// The coincident pair (an edge of the tetrahedron seen end-on).
        pair: [u8; 2],
    },
}

/// A triangle fan over the five points `[v_0, v_1, v_2, v_3, v_t]` (see the module
/// documentation for the layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Fan {
    indices: [u8; 6],
    len: u8,
}

impl Fan {
    /// The empty fan of a degenerate projection.
    pub const EMPTY: Fan = Fan {
        indices: [0; 6],
        len: 0,
    };

    /// The fan's vertex indices in drawing order (the seeds' `indices`, `cnt` of them): empty,
    /// or 3 to 6 indices starting with the thick vertex 4.
    pub fn indices(&self) -> &[u8] {
        let len = usize::from(self.len).min(self.indices.len());
        &self.indices[..len]
    }

    /// Number of fan vertices: the seeds' `cnt`, 0 or 3 to 6.
    pub const fn vertex_count(&self) -> usize {
        self.len as usize
    }

    /// Number of triangles, `cnt - 2` (0 when empty).
    pub const fn triangle_count(&self) -> usize {
        (self.len as usize).saturating_sub(2)
    }

    /// Triangle `i` as `(4, rim_i, rim_{i+1})`, counter-clockwise; `None` past the end.
    pub fn triangle(&self, i: usize) -> Option<[u8; 3]> {
        if i < self.triangle_count() {
            Some([self.indices[0], self.indices[i + 1], self.indices[i + 2]])
        } else {
            None
        }
    }

    /// The triangles, in fan order.
    pub fn triangles(&self) -> impl Iterator<Item = [u8; 3]> + '_ {
        (0..self.triangle_count()).filter_map(|i| self.triangle(i))
    }
}

/// One entry of the ternary truth table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TableEntry {
    /// The ternary code `27 t_1 + 9 t_2 + 3 t_3 + t_4`, equal to the entry's index.
    pub code: u8,
    /// The signs of the four tests: `O(0,1,2)`, `O(0,1,3)`, `O(0,2,3)`, `O(1,2,3)`.
    pub tests: [Sign; 4],
    /// The projection class.
    pub class: ProjectionClass,
    /// Which vertices make up the thick vertex.
    pub thick: ThickTopology,
    /// The seeds' `RGBA` texel: the vertex order `o` for which the lines `v_o0 v_o2` and
    /// `v_o1 v_o3` meet where the thick vertex is computed. Class 2: the two crossing edges
    /// (the crossing is the thick vertex). Class 1: `o2` is the interior vertex, `o0` a face
    /// vertex and `o1 o3` the opposite face edge; the line from `o0` through `o2` meets that
    /// edge at the point from which the face point behind `o2` is interpolated (Shirley and
    /// Tuchman's construction, `000` eq. 3.1). Class 3: apex `o0`, on-edge vertex `o2`, edge
    /// `o1 o3`; they meet at `o2`. Class 4: `o0 = o1` is the coincident pair, which both lines
    /// pass through. The face `o0 o1 o3` (class 1), the quadrilateral `o0 o1 o2 o3` (class 2)
    /// and the triangles `o0 o1 o3` (class 3) and `o0 o2 o3` (class 4) are counter-clockwise.
    /// `None` for degenerate entries.
    pub order: Option<[u8; 4]>,
    /// The triangle fan.
    pub fan: Fan,
}

impl TableEntry {
    /// Whether the entry is one of the 50 valid cases (classes 1 to 4).
    pub const fn is_valid(&self) -> bool {
        !self.class.is_degenerate()
    }
}

/// The ternary code of four test signs (seed `000` eq. 4.1): `27 t_1 + 9 t_2 + 3 t_3 + t_4`
/// with `t_i = sign_i + 1`.
pub const fn ternary_code(tests: [Sign; 4]) -> u8 {
    tests[0].ternary() * 27 + tests[1].ternary() * 9 + tests[2].ternary() * 3 + tests[3].ternary()
}

/// The four test signs of a code; `None` when `code > 80`.
pub const fn decode_code(code: u8) -> Option<[Sign; 4]> {
    if code as usize >= TABLE_SIZE {
        return None;
    }
    let t = [code / 27, (code / 9) % 3, (code / 3) % 3, code % 3];
    match (
        Sign::from_ternary(t[0]),
        Sign::from_ternary(t[1]),
        Sign::from_ternary(t[2]),
        Sign::from_ternary(t[3]),
    ) {
        (Some(a), Some(b), Some(c), Some(d)) => Some([a, b, c, d]),
        _ => None,
    }
}

/// The four tests of seed `000` figure 4.3, computed exactly: the orientations of the
/// projected faces `012`, `013`, `023` and `123`.
pub fn projection_tests(projected: [DVec2; 4]) -> [Sign; 4] {
    let [v0, v1, v2, v3] = projected;
    [
        orient2d(v0, v1, v2),
        orient2d(v0, v1, v3),
        orient2d(v0, v2, v3),
        orient2d(v1, v2, v3),
    ]
}

/// The orientation sign of the projected triangle `(i, j, k)` (distinct indices) implied by the
/// four test signs: the sign of the sorted face, times the parity of the permutation.
const fn triple_sign(tests: [i8; 4], i: u8, j: u8, k: u8) -> i8 {
    let mut p = [i, j, k];
    let mut parity = 1i8;
    if p[0] > p[1] {
        let t = p[0];
        p[0] = p[1];
        p[1] = t;
        parity = -parity;
    }
    if p[1] > p[2] {
        let t = p[1];
        p[1] = p[2];
        p[2] = t;
        parity = -parity;
    }
    if p[0] > p[1] {
        let t = p[0];
        p[0] = p[1];
        p[1] = t;
        parity = -parity;
    }
    // The omitted vertex m is 6 - (sum of the face); the face omitting m is test 3 - m.
    let omitted = 6 - (p[0] + p[1] + p[2]);
    parity * tests[(3 - omitted) as usize]
}

const fn degenerate_entry(code: u8, tests: [Sign; 4], reason: DegenerateReason) -> TableEntry {
    TableEntry {
        code,
        tests,
        class: ProjectionClass::Degenerate(reason),
        thick: ThickTopology::None,
        order: None,
        fan: Fan::EMPTY,
    }
}

const fn sorted2(a: u8, b: u8) -> [u8; 2] {
    if a < b {
        [a, b]
    } else {
        [b, a]
    }
}

/// Builds the entry of one code from the signs of the affine dependency (module docs).
const fn build_entry(code: u8) -> TableEntry {
    let tests = match decode_code(code) {
        Some(t) => t,
        None => [Sign::Zero; 4],
    };
    let t = [
        tests[0].as_i8(),
        tests[1].as_i8(),
        tests[2].as_i8(),
        tests[3].as_i8(),
    ];
    // λ_m = (-1)^m O(face without m).
    let lambda = [t[3], -t[2], t[1], -t[0]];
    let mut pos = [0u8; 4];
    let mut neg = [0u8; 4];
    let mut zero = [0u8; 4];
    let (mut np, mut nn, mut nz) = (0usize, 0usize, 0usize);
    let mut m = 0;
    while m < 4 {
        if lambda[m] > 0 {
            pos[np] = m as u8;
            np += 1;
        } else if lambda[m] < 0 {
            neg[nn] = m as u8;
            nn += 1;
        } else {
            zero[nz] = m as u8;
            nz += 1;
        }
        m += 1;
    }
    if nz == 4 {
        return degenerate_entry(code, tests, DegenerateReason::Collinear);
    }
    if np == 0 || nn == 0 {
        return degenerate_entry(code, tests, DegenerateReason::Inconsistent);
    }
    // The lone vertex and the others, when one side of the partition has a single vertex.
    let (lone, rest) = if np == 1 {
        (pos[0], neg)
    } else {
        (neg[0], pos)
    };
    match nz {
        // Class 4: λ_p = -λ_q and the others zero: v_p = v_q.
        2 => {
            let pair = sorted2(pos[0], neg[0]);
            let p = pair[0];
            let (mut k, mut l) = (zero[0], zero[1]);
            if triple_sign(t, p, k, l) < 0 {
                let s = k;
                k = l;
                l = s;
            }
            TableEntry {
                code,
                tests,
                class: ProjectionClass::Class4,
                thick: ThickTopology::Coincident { pair },
                order: Some([p, pair[1], k, l]),
                fan: Fan {
                    indices: [4, k, l, 0, 0, 0],
                    len: 3,
                },
            }
        }
        // Class 3: the lone vertex is a strict convex combination of the pair; the zero one
        // is the apex.
        1 => {
            let w = zero[0];
            let edge = sorted2(rest[0], rest[1]);
            let (mut e, mut f) = (edge[0], edge[1]);
            if triple_sign(t, w, e, f) < 0 {
                let s = e;
                e = f;
                f = s;
            }
            TableEntry {
                code,
                tests,
                class: ProjectionClass::Class3,
                thick: ThickTopology::OnEdge {
                    vertex: lone,
                    edge,
                    apex: w,
                },
                order: Some([w, e, lone, f]),
                fan: Fan {
                    indices: [4, f, w, e, 0, 0],
                    len: 4,
                },
            }
        }
        _ => {
            if np == 1 || nn == 1 {
                // Class 1: the lone vertex is a strict convex combination of the other three.
                let face = [rest[0], rest[1], rest[2]];
                let (i, mut j, mut l) = (face[0], face[1], face[2]);
                if triple_sign(t, i, j, l) < 0 {
                    let s = j;
                    j = l;
                    l = s;
                }
                TableEntry {
                    code,
                    tests,
                    class: ProjectionClass::Class1,
                    thick: ThickTopology::Interior { vertex: lone, face },
                    order: Some([i, j, lone, l]),
                    fan: Fan {
                        indices: [4, i, j, l, i, 0],
                        len: 5,
                    },
                }
            } else {
                // Class 2: the segment of the positive pair crosses that of the negative pair.
                let (same, other) = if lambda[0] > 0 {
                    (pos, neg)
                } else {
                    (neg, pos)
                };
                let a = 0u8;
                let b = same[1];
                let cd = sorted2(other[0], other[1]);
                let (mut c, mut d) = (cd[0], cd[1]);
                if triple_sign(t, a, c, b) < 0 {
                    let s = c;
                    c = d;
                    d = s;
                }
                TableEntry {
                    code,
                    tests,
                    class: ProjectionClass::Class2,
                    thick: ThickTopology::Crossing {
                        edges: [[a, b], cd],
                    },
                    order: Some([a, c, b, d]),
                    fan: Fan {
                        indices: [4, a, c, b, d, a],
                        len: 6,
                    },
                }
            }
        }
    }
}

const fn build_table() -> [TableEntry; TABLE_SIZE] {
    let mut table =
        [degenerate_entry(0, [Sign::Zero; 4], DegenerateReason::Inconsistent); TABLE_SIZE];
    let mut code = 0;
    while code < TABLE_SIZE {
        table[code] = build_entry(code as u8);
        code += 1;
    }
    table
}

/// The ternary truth table (seed `000` table 4.1), indexed by [`ternary_code`]; built at
/// compile time from the sign analysis of the module documentation.
pub static TERNARY_TABLE: [TableEntry; TABLE_SIZE] = build_table();

// -------------------------------------------------------------------------------------------
// Classification of one projected tetrahedron
// -------------------------------------------------------------------------------------------

/// The thick vertex and the parameters locating it on the tetrahedron's projected elements.
///
/// The parameters are in screen space, along the *projected* edges and faces. Under an
/// orthographic projection they are also the 3D parameters; under a perspective projection
/// convert them with the vertices' clip `w` before interpolating depth or scalar: along an
/// edge `a → b`, the 3D parameter is `s = u w_a / ((1 - u) w_b + u w_a)`; on a face, the 3D
/// barycentrics are proportional to `β_i / w_i`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThickKind {
    /// Class 1: the ray through the interior vertex `vertex` meets the face `face` at the
    /// point with these barycentric coordinates (`v_vertex ≈ Σ β_i v_face[i]`, `β_i ≥ 0`,
    /// `Σ β_i = 1`); the thick segment joins that vertex to that face point.
    Interior {
        /// The interior projected vertex.
        vertex: u8,
        /// The opposite face, sorted.
        face: [u8; 3],
        /// Barycentric coordinates of the vertex in the face's projection.
        barycentric: [f64; 3],
    },
    /// Class 2: the crossing point is `v_a + params[0] (v_b - v_a)` on the first edge
    /// `[a, b]` and `v_c + params[1] (v_d - v_c)` on the second `[c, d]`, both in `[0, 1]`;
    /// the thick segment joins the two edge points (one is the entry, the other the exit).
    Crossing {
        /// The two crossing edges, as in [`ThickTopology::Crossing`].
        edges: [[u8; 2]; 2],
        /// The crossing's parameters along the two edges.
        params: [f64; 2],
    },
    /// Class 3: `v_vertex ≈ v_e + t (v_f - v_e)` with `edge = [e, f]`, `t` in `[0, 1]`; the
    /// thick segment joins the vertex to that point of the edge.
    OnEdge {
        /// The projected vertex on the edge.
        vertex: u8,
        /// The edge, sorted.
        edge: [u8; 2],
        /// The fourth vertex.
        apex: u8,
        /// The vertex's parameter along the edge.
        t: f64,
    },
    /// Class 4: the thick segment is the edge `pair` itself, seen end-on.
    Coincident {
        /// The coincident pair, sorted.
        pair: [u8; 2],
    },
}

impl ThickKind {
    /// The combinatorial part, as stored in the table.
    pub fn topology(&self) -> ThickTopology {
        match *self {
            ThickKind::Interior { vertex, face, .. } => ThickTopology::Interior { vertex, face },
            ThickKind::Crossing { edges, .. } => ThickTopology::Crossing { edges },
            ThickKind::OnEdge {
                vertex, edge, apex, ..
            } => ThickTopology::OnEdge { vertex, edge, apex },
            ThickKind::Coincident { pair } => ThickTopology::Coincident { pair },
        }
    }
}

/// The thick vertex of a non-degenerate projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThickVertex {
    /// Its screen-space position (point 4 of the fan). For classes 1, 3 and 4 it is exactly a
    /// projected vertex; for class 2 it is the computed crossing, clamped to the bounding box
    /// of the projection.
    pub position: DVec2,
    /// What it is, with its parameters.
    pub kind: ThickKind,
}

/// The classification of one projected tetrahedron.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Classification {
    /// The ternary code (index into [`TERNARY_TABLE`]); `None` for non-finite input.
    pub code: Option<u8>,
    /// The projection class.
    pub class: ProjectionClass,
    /// The triangle fan over `[v_0, v_1, v_2, v_3, v_t]`; empty when degenerate.
    pub fan: Fan,
    /// The thick vertex; `None` when degenerate.
    pub thick: Option<ThickVertex>,
}

impl Classification {
    /// The table entry of the code, if any.
    pub fn entry(&self) -> Option<&'static TableEntry> {
        self.code.and_then(|c| TERNARY_TABLE.get(usize::from(c)))
    }

    /// The five points the fan indexes: the projected vertices and the thick vertex (the
    /// first projected vertex stands in for it when the projection is degenerate).
    pub fn points(&self, projected: [DVec2; 4]) -> [DVec2; 5] {
        let t = self.thick.map_or(projected[0], |t| t.position);
        [projected[0], projected[1], projected[2], projected[3], t]
    }
}

/// Classifies the projection of a tetrahedron: four exact tests, one table lookup, then the
/// thick vertex's position and parameters.
///
/// `projected` holds the screen-space positions of the vertices `0..4`. The class, the fan and
/// the thick vertex's topology are exact (they depend only on exactly evaluated signs); the
/// thick vertex's parameters and, for class 2, its position are floating-point
/// approximations, clamped to their valid ranges so that they are always usable. NaN or
/// infinite coordinates give [`DegenerateReason::NonFinite`]; four collinear projected
/// vertices give [`DegenerateReason::Collinear`]. Never panics, never allocates.
pub fn classify(projected: [DVec2; 4]) -> Classification {
    if !projected.iter().all(|p| p.is_finite()) {
        return Classification {
            code: None,
            class: ProjectionClass::Degenerate(DegenerateReason::NonFinite),
            fan: Fan::EMPTY,
            thick: None,
        };
    }
    let tests = projection_tests(projected);
    let code = ternary_code(tests);
    let entry = &TERNARY_TABLE[usize::from(code) % TABLE_SIZE];
    Classification {
        code: Some(code),
        class: entry.class,
        fan: entry.fan,
        thick: thick_vertex(&projected, entry),
    }
}

/// Twice the signed area of `a b c`, in floating point.
#[inline]
fn area2(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// The points scaled by a power of two that brings the largest coordinate into `[1, 2)`, so
/// that the parameter computations neither overflow nor lose everything to underflow
/// (parameters are invariant under scaling).
fn normalized(v: &[DVec2; 4]) -> [DVec2; 4] {
    let m = v
        .iter()
        .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
    if !(m > 0.0 && m.is_finite()) {
        return *v;
    }
    let e = m.log2().floor();
    if !e.is_finite() {
        return *v;
    }
    let k = -(e as i32);
    let f1 = 2f64.powi(k / 2);
    let f2 = 2f64.powi(k - k / 2);
    v.map(|p| p * f1 * f2)
}

/// Parameter along `a → b` of its crossing with the line `c d`.
fn crossing_param(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    let na = area2(c, d, a);
    let nb = area2(c, d, b);
    unit_or_half(na / (na - nb))
}

fn unit_or_half(x: f64) -> f64 {
    if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.5
    }
}

fn thick_vertex(v: &[DVec2; 4], entry: &TableEntry) -> Option<ThickVertex> {
    thick_vertex_scaled(v, &normalized(v), entry)
}

/// The thick vertex of `entry` for the points `v`, with its parameters computed on `n`, the
/// same points scaled by a power of two (bit-identical parameters; `n = v` is fine when the
/// coordinates neither overflow nor underflow, as on the rasterizer's sub-pixel grid).
pub(crate) fn thick_vertex_scaled(
    v: &[DVec2; 4],
    n: &[DVec2; 4],
    entry: &TableEntry,
) -> Option<ThickVertex> {
    let p = |i: u8| v[usize::from(i) % 4];
    let q = |i: u8| n[usize::from(i) % 4];
    let tests = [
        entry.tests[0].as_i8(),
        entry.tests[1].as_i8(),
        entry.tests[2].as_i8(),
        entry.tests[3].as_i8(),
    ];
    match entry.thick {
        ThickTopology::None => None,
        ThickTopology::Interior { vertex: k, face } => {
            let [i, j, l] = face;
            let s = f64::from(triple_sign(tests, i, j, l));
            let raw = [
                s * area2(q(k), q(j), q(l)),
                s * area2(q(i), q(k), q(l)),
                s * area2(q(i), q(j), q(k)),
            ]
            .map(|w| if w > 0.0 { w } else { 0.0 });
            let sum = raw[0] + raw[1] + raw[2];
            let barycentric = if sum > 0.0 && sum.is_finite() {
                raw.map(|w| w / sum)
            } else {
                [1.0 / 3.0; 3]
            };
            Some(ThickVertex {
                position: p(k),
                kind: ThickKind::Interior {
                    vertex: k,
                    face,
                    barycentric,
                },
            })
        }
        ThickTopology::Crossing { edges } => {
            let [[a, b], [c, d]] = edges;
            let u = crossing_param(q(a), q(b), q(c), q(d));
            let w = crossing_param(q(c), q(d), q(a), q(b));
            let lo = v.iter().fold(DVec2::splat(f64::INFINITY), |m, x| m.min(*x));
            let hi = v
                .iter()
                .fold(DVec2::splat(f64::NEG_INFINITY), |m, x| m.max(*x));
            let position = (p(a) * (1.0 - u) + p(b) * u).max(lo).min(hi);
            Some(ThickVertex {
                position,
                kind: ThickKind::Crossing {
                    edges,
                    params: [u, w],
                },
            })
        }
        ThickTopology::OnEdge { vertex, edge, apex } => {
            let [e, f] = edge;
            let d = q(f) - q(e);
            let t = unit_or_half((q(vertex) - q(e)).dot(d) / d.length_squared());
            Some(ThickVertex {
                position: p(vertex),
                kind: ThickKind::OnEdge {
                    vertex,
                    edge,
                    apex,
                    t,
                },
            })
        }
        ThickTopology::Coincident { pair } => Some(ThickVertex {
            position: p(pair[0]),
            kind: ThickKind::Coincident { pair },
        }),
    }
}

#[cfg(test)]
mod tests;
