//! The Cholesky factor of a symmetric positive definite matrix made of 6 × 6 blocks, one block
//! row per body, with off-diagonal blocks where two bodies touch: the Newton system of an
//! island's implicit step.
//!
//! The bodies are eliminated in minimum-degree order (ties by index, so the order depends on
//! the graph alone): the elimination of a body joins all its remaining neighbours, and the
//! body with the fewest neighbours left goes first. The graph's structure is analysed once
//! ([`BlockCholesky::analyse`]) and factored for each Newton iteration ([`factor`]). A stack
//! or a pile is a graph of few neighbours per body; the factor fills in little and costs far
//! less than a dense one over the island's `6 n` unknowns.
//!
//! A general sparse solver would treat each of the 36 entries of a block as its own unknown
//! pattern; here blocks are the unit, so the structure is a body graph of tens to thousands of
//! nodes and the dense 6 × 6 kernels stay in registers.
//!
//! [`factor`]: BlockCholesky::factor

use crate::math::Real;

/// A dense 6 × 6 block, rows of 6.
pub(crate) type Block = [[Real; 6]; 6];

/// A block column of unknowns or right-hand sides, one per body.
pub(crate) type Column = [Real; 6];

/// The zero block.
pub(crate) const ZERO: Block = [[0.0; 6]; 6];

/// The analysed structure and, once [`factor`](Self::factor)ed, the factor `L` (`A = L Lᵀ`).
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockCholesky {
    /// Bodies in elimination order.
    order: Vec<usize>,
    /// Each body's place in `order`.
    place: Vec<usize>,
    /// For each place `k`, the later places `i > k` where `L` has a block in column `k`,
    /// ascending.
    rows: Vec<Vec<usize>>,
    /// `L`'s diagonal blocks by place (lower triangular).
    diagonal: Vec<Block>,
    /// `L`'s blocks below the diagonal, beside `rows`.
    below: Vec<Vec<Block>>,
}

/// The matrix was not positive definite (a pivot at or below zero, or not finite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NotPositiveDefinite;

impl BlockCholesky {
    /// The structure of `n` bodies joined by `edges` (pairs of distinct bodies, in any order,
    /// repeats allowed): the elimination order and where the factor has blocks.
    pub(crate) fn analyse(n: usize, edges: &[(usize, usize)]) -> Self {
        use std::collections::BTreeSet;
        let mut neighbours: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
        for &(a, b) in edges {
            if a != b {
                neighbours[a].insert(b);
                neighbours[b].insert(a);
            }
        }
        // Bodies keyed by (neighbours left, index): the first is the next to eliminate.
        let mut queue: BTreeSet<(usize, usize)> =
            (0..n).map(|i| (neighbours[i].len(), i)).collect();
        let mut order = Vec::with_capacity(n);
        let mut columns: Vec<Vec<usize>> = Vec::with_capacity(n);
        while let Some((_, u)) = queue.pop_first() {
            let joined: Vec<usize> = neighbours[u].iter().copied().collect();
            for &a in &joined {
                queue.remove(&(neighbours[a].len(), a));
                neighbours[a].remove(&u);
            }
            for (k, &a) in joined.iter().enumerate() {
                for &b in &joined[k + 1..] {
                    neighbours[a].insert(b);
                    neighbours[b].insert(a);
                }
            }
            for &a in &joined {
                queue.insert((neighbours[a].len(), a));
            }
            neighbours[u].clear();
            order.push(u);
            columns.push(joined);
        }
        let mut place = vec![0; n];
        for (k, &u) in order.iter().enumerate() {
            place[u] = k;
        }
        let rows: Vec<Vec<usize>> = columns
            .into_iter()
            .map(|c| {
                let mut r: Vec<usize> = c.into_iter().map(|b| place[b]).collect();
                r.sort_unstable();
                r
            })
            .collect();
        let below = rows.iter().map(|r| vec![ZERO; r.len()]).collect();
        Self { order, place, rows, diagonal: vec![ZERO; n], below }
    }

    /// Blocks of the factor below the diagonal: a measure of the fill.
    #[cfg(test)]
    pub(crate) fn blocks_below(&self) -> usize {
        self.rows.iter().map(Vec::len).sum()
    }

    /// Factors the matrix with diagonal blocks `diagonal[body]` and, for each edge `(a, b)` of
    /// the analysed structure, the block `A_ab` (rows of `a`, columns of `b`) in `off` (its
    /// transpose is `A_ba`; blocks of repeated edges add up).
    pub(crate) fn factor(
        &mut self,
        diagonal: &[Block],
        off: &[((usize, usize), Block)],
    ) -> Result<(), NotPositiveDefinite> {
        let n = self.order.len();
        for k in 0..n {
            self.diagonal[k] = diagonal[self.order[k]];
            self.below[k].iter_mut().for_each(|b| *b = ZERO);
        }
        for &((a, b), block) in off {
            let (pa, pb) = (self.place[a], self.place[b]);
            // The block at row max(pa, pb), column min(pa, pb).
            let (column, row, block) =
                if pa < pb { (pa, pb, transpose(&block)) } else { (pb, pa, block) };
            let slot = self.rows[column].binary_search(&row).expect("an edge of the structure");
            add_to(&mut self.below[column][slot], &block);
        }
        for k in 0..n {
            cholesky_in_place(&mut self.diagonal[k])?;
            let l_kk = self.diagonal[k];
            // L_ik = A_ik L_kk⁻ᵀ.
            for block in self.below[k].iter_mut() {
                *block = solve_right_transposed(block, &l_kk);
            }
            // A_ij −= L_ik L_jkᵀ for the later places i >= j in column k.
            let (done, rest) = self.below.split_at_mut(k + 1);
            let column = &done[k];
            let rows = &self.rows[k];
            for (x, &j) in rows.iter().enumerate() {
                let l_jk = &column[x];
                subtract_product(&mut self.diagonal[j], l_jk, l_jk);
                for (y, &i) in rows.iter().enumerate().skip(x + 1) {
                    let slot = self.rows[j].binary_search(&i).expect("the fill holds the clique");
                    subtract_product(&mut rest[j - k - 1][slot], &column[y], l_jk);
                }
            }
        }
        Ok(())
    }

    /// Solves `A x = b` with the factor, `b` given and returned by body.
    pub(crate) fn solve(&self, x: &mut [Column]) {
        let n = self.order.len();
        let mut y: Vec<Column> = self.order.iter().map(|&u| x[u]).collect();
        // L z = b.
        for k in 0..n {
            y[k] = forward(&self.diagonal[k], &y[k]);
            let z = y[k];
            for (block, &i) in self.below[k].iter().zip(&self.rows[k]) {
                let p = multiply(block, &z);
                for r in 0..6 {
                    y[i][r] -= p[r];
                }
            }
        }
        // Lᵀ x = z.
        for k in (0..n).rev() {
            let mut rhs = y[k];
            for (block, &i) in self.below[k].iter().zip(&self.rows[k]) {
                let p = multiply_transposed(block, &y[i]);
                for r in 0..6 {
                    rhs[r] -= p[r];
                }
            }
            y[k] = backward(&self.diagonal[k], &rhs);
        }
        for (k, &u) in self.order.iter().enumerate() {
            x[u] = y[k];
        }
    }
}

/// `a += b`.
pub(crate) fn add_to(a: &mut Block, b: &Block) {
    for r in 0..6 {
        for c in 0..6 {
            a[r][c] += b[r][c];
        }
    }
}

/// `Aᵀ`.
pub(crate) fn transpose(a: &Block) -> Block {
    let mut t = ZERO;
    for r in 0..6 {
        for c in 0..6 {
            t[c][r] = a[r][c];
        }
    }
    t
}

/// `a −= b cᵀ`.
fn subtract_product(a: &mut Block, b: &Block, c: &Block) {
    for r in 0..6 {
        for s in 0..6 {
            let mut sum = 0.0;
            for k in 0..6 {
                sum += b[r][k] * c[s][k];
            }
            a[r][s] -= sum;
        }
    }
}

/// `A x`.
pub(crate) fn multiply(a: &Block, x: &Column) -> Column {
    let mut y = [0.0; 6];
    for r in 0..6 {
        y[r] = (0..6).map(|c| a[r][c] * x[c]).sum();
    }
    y
}

/// `Aᵀ x`.
fn multiply_transposed(a: &Block, x: &Column) -> Column {
    let mut y = [0.0; 6];
    for c in 0..6 {
        y[c] = (0..6).map(|r| a[r][c] * x[r]).sum();
    }
    y
}

/// Overwrites the lower triangle of a symmetric positive definite block with its Cholesky
/// factor `L` (`A = L Lᵀ`) and zeroes the upper.
fn cholesky_in_place(a: &mut Block) -> Result<(), NotPositiveDefinite> {
    for j in 0..6 {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err(NotPositiveDefinite);
        }
        let d = d.sqrt();
        a[j][j] = d;
        for i in j + 1..6 {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k];
            }
            a[i][j] = s / d;
        }
        for c in j + 1..6 {
            a[j][c] = 0.0;
        }
    }
    Ok(())
}

/// `X = B L⁻ᵀ`, i.e. `X Lᵀ = B`, for lower triangular `L`.
fn solve_right_transposed(b: &Block, l: &Block) -> Block {
    let mut x = ZERO;
    for r in 0..6 {
        for c in 0..6 {
            let mut s = b[r][c];
            for k in 0..c {
                s -= x[r][k] * l[c][k];
            }
            x[r][c] = s / l[c][c];
        }
    }
    x
}

/// `L⁻¹ b` for lower triangular `L`.
fn forward(l: &Block, b: &Column) -> Column {
    let mut x = [0.0; 6];
    for r in 0..6 {
        let s: Real = (0..r).map(|k| l[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / l[r][r];
    }
    x
}

/// `L⁻ᵀ b` for lower triangular `L`.
fn backward(l: &Block, b: &Column) -> Column {
    let mut x = [0.0; 6];
    for r in (0..6).rev() {
        let s: Real = (r + 1..6).map(|k| l[k][r] * x[k]).sum();
        x[r] = (b[r] - s) / l[r][r];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random symmetric positive definite block matrix on a graph (a chain with shortcuts,
    /// a star and a grid): the factor solves it to round-off, against the dense product, and
    /// a minimum-degree order keeps a chain's factor free of fill.
    #[test]
    fn the_factor_solves_block_systems_on_a_graph() {
        let mut state = 17u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as Real / (1u64 << 53) as Real - 0.5
        };
        let grids: [(usize, Vec<(usize, usize)>); 3] = [
            (12, (0..11).map(|i| (i, i + 1)).chain([(0, 5), (3, 9)]).collect()),
            (9, (1..9).map(|i| (0, i)).collect()),
            (16, (0..16).flat_map(|i| [(i, (i + 1) % 16), (i, (i + 4) % 16)]).collect()),
        ];
        for (n, edges) in grids {
            let mut off = Vec::new();
            let mut diagonal = vec![ZERO; n];
            for &(a, b) in &edges {
                let mut block = ZERO;
                block.iter_mut().flatten().for_each(|x| *x = rnd());
                off.push(((a, b), block));
                // Diagonal dominance keeps the whole positive definite.
                for r in 0..6 {
                    let row: Real = block[r].iter().map(|x| x.abs()).sum();
                    let col: Real = (0..6).map(|c| block[c][r].abs()).sum();
                    diagonal[a][r][r] += row + 0.1;
                    diagonal[b][r][r] += col + 0.1;
                }
            }
            for d in diagonal.iter_mut() {
                for r in 0..6 {
                    d[r][r] += 1.0;
                    for c in 0..r {
                        let x = 0.01 * rnd();
                        d[r][c] += x;
                        d[c][r] += x;
                    }
                }
            }
            let mut factor = BlockCholesky::analyse(n, &edges);
            factor.factor(&diagonal, &off).unwrap();
            let x_true: Vec<Column> = (0..n).map(|_| [0; 6].map(|_| rnd())).collect();
            // b = A x.
            let mut b: Vec<Column> = (0..n).map(|i| multiply(&diagonal[i], &x_true[i])).collect();
            for &((a, c), block) in &off {
                let p = multiply(&block, &x_true[c]);
                let q = multiply_transposed(&block, &x_true[a]);
                for r in 0..6 {
                    b[a][r] += p[r];
                    b[c][r] += q[r];
                }
            }
            factor.solve(&mut b);
            for (x, t) in b.iter().zip(&x_true) {
                for r in 0..6 {
                    assert!((x[r] - t[r]).abs() < 1e-10, "{} against {}", x[r], t[r]);
                }
            }
        }
        // A chain eliminated from its ends fills nothing in.
        let chain: Vec<(usize, usize)> = (0..9).map(|i| (i, i + 1)).collect();
        assert_eq!(BlockCholesky::analyse(10, &chain).blocks_below(), 9);
    }

    /// A block that is not positive definite is refused, not factored into NaN.
    #[test]
    fn an_indefinite_matrix_is_refused() {
        let mut d = ZERO;
        for r in 0..6 {
            d[r][r] = 1.0;
        }
        d[2][2] = -1.0;
        let mut factor = BlockCholesky::analyse(1, &[]);
        assert_eq!(factor.factor(&[d], &[]), Err(NotPositiveDefinite));
    }
}
