//! The reverse Cuthill–McKee order of a symmetric pattern: a breadth-first
//! numbering from a pseudo-peripheral node, each node's unnumbered
//! neighbours taken by increasing degree, reversed (Cuthill & McKee 1969;
//! George & Liu, *Computer Solution of Large Sparse Positive Definite
//! Systems*, 1981, §4.3 and §4.4.2 for the starting node). It keeps each
//! row's entries near the diagonal, so the envelope of `C = B S⁻¹ Bᵀ` of a
//! closed-loop mechanism (the N-four-bar, whose constraints' own order
//! spreads a loop's rows apart) stays narrow.

use crate::csc::Csc;

/// The order (`fwd[k]` is the row placed `k`-th) of the symmetric pattern
/// `a`, stored with both triangles; each connected component is numbered
/// on its own.
pub(crate) fn reverse_cuthill_mckee(a: &Csc) -> Vec<usize> {
    let n = a.n;
    let degree: Vec<usize> = (0..n)
        .map(|j| a.column(j).iter().filter(|&&i| i != j).count())
        .collect();
    let mut by_degree: Vec<usize> = (0..n).collect();
    by_degree.sort_by_key(|&j| degree[j]);
    let mut search = Search {
        depth: vec![usize::MAX; n],
        queue: Vec::new(),
        visited: vec![false; n],
    };
    let mut order = Vec::with_capacity(n);
    let mut next = Vec::new();
    for &seed in &by_degree {
        if search.visited[seed] {
            continue;
        }
        let start = search.peripheral(a, &degree, seed);
        // Cuthill–McKee: breadth first, neighbours by increasing degree.
        let mut head = order.len();
        search.visited[start] = true;
        order.push(start);
        while head < order.len() {
            let j = order[head];
            head += 1;
            next.clear();
            next.extend(a.column(j).iter().copied().filter(|&i| !search.visited[i]));
            next.sort_unstable_by_key(|&i| (degree[i], i));
            for &i in &next {
                search.visited[i] = true;
                order.push(i);
            }
        }
    }
    order.reverse();
    order
}

/// Breadth-first searches over the nodes not yet numbered.
struct Search {
    /// Each node's distance from the root of the current search
    /// (`usize::MAX`: not reached; reset after each search).
    depth: Vec<usize>,
    /// The nodes reached, in order.
    queue: Vec<usize>,
    /// Numbered already (an earlier component).
    visited: Vec<bool>,
}

impl Search {
    /// The nodes reachable from `root` into `queue`; returns the largest
    /// depth (the root's eccentricity in its component).
    fn from(&mut self, a: &Csc, root: usize) -> usize {
        for &i in &self.queue {
            self.depth[i] = usize::MAX;
        }
        self.queue.clear();
        self.queue.push(root);
        self.depth[root] = 0;
        let mut head = 0;
        while head < self.queue.len() {
            let j = self.queue[head];
            head += 1;
            for &i in a.column(j) {
                if !self.visited[i] && self.depth[i] == usize::MAX {
                    self.depth[i] = self.depth[j] + 1;
                    self.queue.push(i);
                }
            }
        }
        // Breadth first: the last node reached is the deepest.
        self.queue.last().map_or(0, |&i| self.depth[i])
    }

    /// A pseudo-peripheral node of `seed`'s component (George & Liu): from
    /// the root, the node of least degree in the last level becomes the root
    /// while that makes the eccentricity grow.
    fn peripheral(&mut self, a: &Csc, degree: &[usize], seed: usize) -> usize {
        let mut root = seed;
        let mut eccentricity = self.from(a, root);
        loop {
            let last = self
                .queue
                .iter()
                .rev()
                .take_while(|&&i| self.depth[i] == eccentricity)
                .min_by_key(|&&i| (degree[i], i))
                .copied();
            let Some(candidate) = last.filter(|&c| c != root) else {
                return root;
            };
            let e = self.from(a, candidate);
            if e <= eccentricity {
                return root;
            }
            (root, eccentricity) = (candidate, e);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The symmetric pattern of the undirected edges `edges` on `n` nodes,
    /// with the diagonal.
    fn pattern(n: usize, edges: &[(usize, usize)]) -> Csc {
        let mut pairs: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        for &(i, j) in edges {
            pairs.extend([(i, j), (j, i)]);
        }
        Csc::from_pairs(n, &pairs)
    }

    /// The largest `|k − l|` over the edges, nodes at their places in `fwd`.
    fn bandwidth(n: usize, edges: &[(usize, usize)], fwd: &[usize]) -> usize {
        let mut inv = vec![0; n];
        for (k, &r) in fwd.iter().enumerate() {
            inv[r] = k;
        }
        edges
            .iter()
            .map(|&(i, j)| inv[i].abs_diff(inv[j]))
            .max()
            .unwrap_or(0)
    }

    #[test]
    fn a_path_numbered_at_random_is_numbered_along_the_path() {
        // The path 0-1-…-9 under the labels of a fixed permutation: its
        // own order has bandwidth 9 apart; any breadth-first order from an
        // end has bandwidth 1.
        let label = [7, 2, 9, 4, 0, 5, 8, 1, 6, 3];
        let edges: Vec<_> = (0..9).map(|k| (label[k], label[k + 1])).collect();
        let fwd = reverse_cuthill_mckee(&pattern(10, &edges));
        let mut sorted = fwd.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..10).collect::<Vec<_>>(), "a permutation");
        assert_eq!(bandwidth(10, &edges, &fwd), 1);
    }

    #[test]
    fn a_ladder_gets_bandwidth_two_and_components_stay_apart() {
        // A ladder of 8 rungs (nodes 2k, 2k+1; rails and rungs), numbered
        // rail by rail (bandwidth 8), and an isolated node and a separate
        // edge: a breadth-first order from one end of the ladder numbers it
        // rung by rung (bandwidth 2, the least for a ladder's triangles of
        // rungs and rails).
        let r = 8;
        let at = |k: usize, side: usize| side * r + k;
        let mut edges = Vec::new();
        for k in 0..r {
            edges.push((at(k, 0), at(k, 1)));
            if k + 1 < r {
                edges.push((at(k, 0), at(k + 1, 0)));
                edges.push((at(k, 1), at(k + 1, 1)));
            }
        }
        edges.push((2 * r + 1, 2 * r + 2));
        let n = 2 * r + 3;
        let fwd = reverse_cuthill_mckee(&pattern(n, &edges));
        assert_eq!(fwd.len(), n);
        assert_eq!(bandwidth(n, &edges, &fwd), 2);
    }
}
