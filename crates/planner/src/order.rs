//! Ordering the candidates: an open path from the start pose (or a tour back to it) through
//! every candidate's slides, each candidate entered in one of a few *variants* (which end of
//! its slide first, which way along the crack), with every variant's reverse among them.
//!
//! * [`Order::NearestNeighbour`]: always the nearest entry next;
//! * [`Order::TwoOpt`]: nearest neighbour, then 2-opt (reversing a stretch reverses its variants),
//!   Or-opt (moving runs of 1–3 candidates, either way round, a single one as any of its
//!   variants) and the best variants (one at a time, then all at once by dynamic programming),
//!   until no move shortens the path; run from [`MULTI_START`] starts (nearest neighbour, and
//!   nearest neighbour begun at each next-nearest candidate), the shortest kept;
//! * [`Order::BruteForce`]: every order (`n!`), the best variants for each by dynamic
//!   programming: the exact optimum, for `n ≤` [`crate::MAX_BRUTE_FORCE`].
//!
//! The cost is the distance travelled with the finger lifted, between candidates and between the
//! slides of one candidate.

use serde::{Deserialize, Serialize};

use crate::geometry::Point;

/// Euclidean distance (no `hypot`: coordinates are bounded by `MAX_COORD_MM`, and this is the
/// inner loop).
#[inline]
fn dist(a: Point, b: Point) -> f64 {
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    (dx * dx + dy * dy).sqrt()
}

/// How candidates are ordered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// In the order given (each candidate's variant still chosen for the shortest path).
    AsGiven,
    /// Nearest neighbour from the start pose.
    NearestNeighbour,
    /// Nearest neighbour improved by 2-opt, Or-opt and variant choice, from several starts (the
    /// default).
    #[default]
    TwoOpt,
    /// Exact, by trying every order (small cases only).
    BruteForce,
}

/// One way of visiting a node: where it is entered and left, the travel inside it, and the
/// index of its reverse (entered where this one leaves).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Ends {
    pub entry: Point,
    pub exit: Point,
    pub internal: f64,
    pub rev: usize,
}

/// The routing problem: nodes with their variants, from `start`, back to it when `ret`.
pub(crate) struct Problem<'a> {
    pub start: Point,
    pub ret: bool,
    pub nodes: &'a [Vec<Ends>],
}

/// Visiting order: (node, variant).
pub(crate) type Route = Vec<(usize, usize)>;

const EPS: f64 = 1e-9;

/// Local searches [`Order::TwoOpt`] runs: from nearest neighbour and from nearest neighbour
/// begun at each of the next nearest candidates.
pub const MULTI_START: usize = 8;

/// How an Or-opt move puts a run back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Insert {
    Forward,
    Reversed,
    /// A single node, as this variant.
    Variant(usize),
}

impl Problem<'_> {
    fn ends(&self, (n, v): (usize, usize)) -> &Ends {
        &self.nodes[n][v]
    }

    fn link(a: Point, b: Option<Point>) -> f64 {
        b.map_or(0.0, |b| dist(a, b))
    }

    /// The total travel of a route.
    pub fn cost(&self, route: &[(usize, usize)]) -> f64 {
        let mut at = self.start;
        let mut c = 0.0;
        for &rv in route {
            let e = self.ends(rv);
            c += dist(at, e.entry) + e.internal;
            at = e.exit;
        }
        if self.ret {
            c += dist(at, self.start);
        }
        c
    }

    fn prev_exit(&self, route: &[(usize, usize)], i: usize) -> Point {
        if i == 0 {
            self.start
        } else {
            self.ends(route[i - 1]).exit
        }
    }

    fn next_entry(&self, route: &[(usize, usize)], j: usize) -> Option<Point> {
        if j + 1 < route.len() {
            Some(self.ends(route[j + 1]).entry)
        } else if self.ret {
            Some(self.start)
        } else {
            None
        }
    }

    /// The route through `order` with the best variants (exact, by dynamic programming).
    pub fn best_variants(&self, order: &[usize]) -> Route {
        if order.is_empty() {
            return Vec::new();
        }
        // cost[v]: best cost of the prefix ending in variant v of the current node.
        let mut back: Vec<Vec<usize>> = Vec::with_capacity(order.len());
        let mut cost: Vec<f64> = self.nodes[order[0]]
            .iter()
            .map(|e| dist(self.start, e.entry) + e.internal)
            .collect();
        back.push(vec![0; cost.len()]);
        for w in order.windows(2) {
            let (prev, cur) = (&self.nodes[w[0]], &self.nodes[w[1]]);
            let mut next = Vec::with_capacity(cur.len());
            let mut from = Vec::with_capacity(cur.len());
            for e in cur {
                let (u, c) = prev
                    .iter()
                    .enumerate()
                    .map(|(u, p)| (u, cost[u] + dist(p.exit, e.entry)))
                    .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
                next.push(c + e.internal);
                from.push(u);
            }
            cost = next;
            back.push(from);
        }
        let last = &self.nodes[order[order.len() - 1]];
        let mut v = (0..last.len())
            .map(|v| {
                let c = cost[v]
                    + if self.ret {
                        dist(last[v].exit, self.start)
                    } else {
                        0.0
                    };
                (v, c)
            })
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
            .0;
        let mut route = vec![(0, 0); order.len()];
        for k in (0..order.len()).rev() {
            route[k] = (order[k], v);
            v = back[k][v];
        }
        route
    }

    /// Nearest neighbour: from where the finger is, the unvisited (node, variant) whose entry is
    /// nearest (plus its internal travel).
    pub fn nearest_neighbour(&self) -> Route {
        self.nearest_neighbour_from(None)
    }

    /// Nearest neighbour, with `first` (node, variant) visited first when given.
    fn nearest_neighbour_from(&self, first: Option<(usize, usize)>) -> Route {
        let n = self.nodes.len();
        let mut visited = vec![false; n];
        let mut route = Vec::with_capacity(n);
        let mut at = self.start;
        if let Some(f) = first {
            visited[f.0] = true;
            route.push(f);
            at = self.ends(f).exit;
        }
        while route.len() < n {
            let mut best = (usize::MAX, 0, f64::INFINITY);
            for (i, vars) in self.nodes.iter().enumerate() {
                if visited[i] {
                    continue;
                }
                for (v, e) in vars.iter().enumerate() {
                    let c = dist(at, e.entry) + e.internal;
                    if c < best.2 {
                        best = (i, v, c);
                    }
                }
            }
            visited[best.0] = true;
            route.push((best.0, best.1));
            at = self.ends((best.0, best.1)).exit;
        }
        route
    }

    /// [`Problem::improve`] from nearest neighbour, and from nearest neighbour forced to begin
    /// with each of the [`MULTI_START`] − 1 next-nearest first entries; the shortest result.
    pub fn multi_start(&self) -> Route {
        let mut firsts: Vec<(f64, usize, usize)> = self
            .nodes
            .iter()
            .enumerate()
            .flat_map(|(i, vars)| {
                vars.iter()
                    .enumerate()
                    .map(move |(v, e)| (dist(self.start, e.entry) + e.internal, i, v))
            })
            .collect();
        firsts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best = self.improve(self.nearest_neighbour());
        let mut best_cost = self.cost(&best);
        let mut tried = vec![best.first().map(|f| f.0)];
        for &(_, i, v) in &firsts {
            if tried.len() >= MULTI_START {
                break;
            }
            if tried.contains(&Some(i)) {
                continue;
            }
            tried.push(Some(i));
            let r = self.improve(self.nearest_neighbour_from(Some((i, v))));
            let c = self.cost(&r);
            if c < best_cost - EPS {
                best = r;
                best_cost = c;
            }
        }
        best
    }

    /// 2-opt, Or-opt and variant moves until none shortens the route.
    pub fn improve(&self, mut route: Route) -> Route {
        let n = route.len();
        if n == 0 {
            return route;
        }
        // Bounded for safety; every applied move shortens the route by more than EPS.
        for _ in 0..10_000 {
            let mut improved = self.two_opt_pass(&mut route)
                | self.or_opt_pass(&mut route)
                | self.variant_pass(&mut route);
            if !improved {
                // The best variants for this order, all at once.
                let order: Vec<usize> = route.iter().map(|rv| rv.0).collect();
                let best = self.best_variants(&order);
                if self.cost(&best) < self.cost(&route) - EPS {
                    route = best;
                    improved = true;
                }
            }
            if !improved {
                break;
            }
        }
        route
    }

    /// Replaces `route` with `candidate` if that is shorter by more than [`EPS`]. The passes
    /// find their moves by local deltas that hold where each node's reverse variant mirrors it
    /// (enters where it leaves and leaves where it enters); where it does not (a slide followed
    /// by a raised pass leaves the finger elsewhere, [`crate::RaisedPass`]) the whole route's
    /// cost decides, so every accepted move shortens the route and the passes end.
    fn take_if_shorter(&self, route: &mut Route, candidate: Route) -> bool {
        if self.cost(&candidate) < self.cost(route) - EPS {
            *route = candidate;
            true
        } else {
            false
        }
    }

    fn two_opt_pass(&self, route: &mut Route) -> bool {
        let n = route.len();
        let mut improved = false;
        for i in 0..n {
            for j in i + 1..n {
                let p = self.prev_exit(route, i);
                let nx = self.next_entry(route, j);
                let (ei, ej) = (self.ends(route[i]), self.ends(route[j]));
                let old = dist(p, ei.entry) + Self::link(ej.exit, nx);
                let new = dist(p, ej.exit) + Self::link(ei.entry, nx);
                if new < old - EPS {
                    let mut moved = route.clone();
                    moved[i..=j].reverse();
                    for rv in &mut moved[i..=j] {
                        rv.1 = self.nodes[rv.0][rv.1].rev;
                    }
                    improved |= self.take_if_shorter(route, moved);
                }
            }
        }
        improved
    }

    fn or_opt_pass(&self, route: &mut Route) -> bool {
        let mut improved = false;
        for len in 1..=3usize {
            let mut i = 0;
            while i + len <= route.len() {
                if route.len() <= len {
                    break;
                }
                let (first, last) = (self.ends(route[i]), self.ends(route[i + len - 1]));
                let p = self.prev_exit(route, i);
                let nx = self.next_entry(route, i + len - 1);
                let gain = dist(p, first.entry) + Self::link(last.exit, nx) - Self::link(p, nx);
                // The route without the run, without building it.
                let rest_len = route.len() - len;
                let rest = |g: usize| if g < i { route[g] } else { route[g + len] };
                let mut best: Option<(f64, usize, Insert)> = None;
                for g in 0..=rest_len {
                    let a = if g == 0 {
                        self.start
                    } else {
                        self.ends(rest(g - 1)).exit
                    };
                    let b = if g < rest_len {
                        Some(self.ends(rest(g)).entry)
                    } else if self.ret {
                        Some(self.start)
                    } else {
                        None
                    };
                    let base = Self::link(a, b);
                    if len == 1 {
                        // A single node goes in with whichever of its variants fits best.
                        let node = route[i].0;
                        for (v, e) in self.nodes[node].iter().enumerate() {
                            let cost = dist(a, e.entry) + e.internal + Self::link(e.exit, b)
                                - base
                                - first.internal;
                            if g == i && v == route[i].1 {
                                continue; // where it is
                            }
                            if cost - gain < -EPS && best.is_none_or(|(c, _, _)| cost < c) {
                                best = Some((cost, g, Insert::Variant(v)));
                            }
                        }
                        continue;
                    }
                    let fwd = dist(a, first.entry) + Self::link(last.exit, b) - base;
                    let rev = dist(a, last.exit) + Self::link(first.entry, b) - base;
                    for (cost, how) in [(fwd, Insert::Forward), (rev, Insert::Reversed)] {
                        if g == i && how == Insert::Forward {
                            continue; // where it is
                        }
                        if cost - gain < -EPS && best.is_none_or(|(c, _, _)| cost < c) {
                            best = Some((cost, g, how));
                        }
                    }
                }
                if let Some((_, g, how)) = best {
                    let mut candidate = route.clone();
                    let mut moved: Vec<(usize, usize)> = candidate.drain(i..i + len).collect();
                    match how {
                        Insert::Forward => {}
                        Insert::Reversed => {
                            moved.reverse();
                            for rv in &mut moved {
                                rv.1 = self.nodes[rv.0][rv.1].rev;
                            }
                        }
                        Insert::Variant(v) => moved[0].1 = v,
                    }
                    candidate.splice(g..g, moved);
                    improved |= self.take_if_shorter(route, candidate);
                }
                i += 1;
            }
        }
        improved
    }

    fn variant_pass(&self, route: &mut Route) -> bool {
        let mut improved = false;
        for i in 0..route.len() {
            let p = self.prev_exit(route, i);
            let nx = self.next_entry(route, i);
            let cost = |e: &Ends| dist(p, e.entry) + e.internal + Self::link(e.exit, nx);
            let node = route[i].0;
            let current = cost(&self.nodes[node][route[i].1]);
            let (v, c) = self.nodes[node]
                .iter()
                .enumerate()
                .map(|(v, e)| (v, cost(e)))
                .fold((route[i].1, current), |a, b| if b.1 < a.1 { b } else { a });
            if c < current - EPS {
                route[i].1 = v;
                improved = true;
            }
        }
        improved
    }

    /// The exact optimum: every order (Heap's algorithm), the best variants of each.
    pub fn brute_force(&self) -> Route {
        let n = self.nodes.len();
        let mut perm: Vec<usize> = (0..n).collect();
        let mut best = self.best_variants(&perm);
        let mut best_cost = self.cost(&best);
        let mut c = vec![0usize; n];
        let mut i = 0;
        while i < n {
            if c[i] < i {
                if i % 2 == 0 {
                    perm.swap(0, i);
                } else {
                    perm.swap(c[i], i);
                }
                let r = self.best_variants(&perm);
                let cost = self.cost(&r);
                if cost < best_cost - EPS {
                    best = r;
                    best_cost = cost;
                }
                c[i] += 1;
                i = 0;
            } else {
                c[i] = 0;
                i += 1;
            }
        }
        best
    }

    /// The route for `order`.
    pub fn solve(&self, order: Order) -> Route {
        match order {
            Order::AsGiven => self.best_variants(&(0..self.nodes.len()).collect::<Vec<_>>()),
            Order::NearestNeighbour => self.nearest_neighbour(),
            Order::TwoOpt => self.multi_start(),
            Order::BruteForce => self.brute_force(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Point nodes (entry = exit, one variant).
    fn points(ps: &[Point]) -> Vec<Vec<Ends>> {
        ps.iter()
            .map(|&p| {
                vec![Ends {
                    entry: p,
                    exit: p,
                    internal: 0.0,
                    rev: 0,
                }]
            })
            .collect()
    }

    /// Segment nodes: two variants, a→b and b→a.
    fn segments(ss: &[(Point, Point)]) -> Vec<Vec<Ends>> {
        ss.iter()
            .map(|&(a, b)| {
                vec![
                    Ends {
                        entry: a,
                        exit: b,
                        internal: 0.0,
                        rev: 1,
                    },
                    Ends {
                        entry: b,
                        exit: a,
                        internal: 0.0,
                        rev: 0,
                    },
                ]
            })
            .collect()
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Nodes whose reverse does not mirror them (a slide of one pass followed by a raised pass
    /// back past its start leaves the finger near where it entered, either way round): the local
    /// search still ends (it looped before its moves were checked on the whole route), never
    /// loses to nearest neighbour, and brute force never loses to it.
    #[test]
    fn local_search_ends_and_holds_where_reverses_do_not_mirror() {
        let mut seed = 11u64;
        for case in 0..200 {
            let n = 1 + case % 8;
            let nodes: Vec<Vec<Ends>> = (0..n)
                .map(|_| {
                    let a = [lcg(&mut seed) * 100.0, lcg(&mut seed) * 100.0];
                    let b = [a[0] + lcg(&mut seed) * 20.0, a[1] + lcg(&mut seed) * 20.0];
                    let near = |p: Point, q: Point| {
                        [p[0] + 0.1 * (p[0] - q[0]), p[1] + 0.1 * (p[1] - q[1])]
                    };
                    vec![
                        Ends {
                            entry: a,
                            exit: near(a, b),
                            internal: dist(a, b),
                            rev: 1,
                        },
                        Ends {
                            entry: b,
                            exit: near(b, a),
                            internal: dist(a, b),
                            rev: 0,
                        },
                    ]
                })
                .collect();
            orders_hold(&nodes, case);
        }
    }

    #[test]
    fn points_on_a_line_are_visited_in_order() {
        let nodes = points(&[[30.0, 0.0], [10.0, 0.0], [20.0, 0.0], [40.0, 0.0]]);
        let p = Problem {
            start: [0.0, 0.0],
            ret: false,
            nodes: &nodes,
        };
        for o in [Order::NearestNeighbour, Order::TwoOpt, Order::BruteForce] {
            let r = p.solve(o);
            assert_eq!(
                r.iter().map(|x| x.0).collect::<Vec<_>>(),
                vec![1, 2, 0, 3],
                "{o:?}"
            );
            assert_eq!(p.cost(&r), 40.0);
        }
        assert_eq!(p.cost(&p.solve(Order::AsGiven)), 30.0 + 20.0 + 10.0 + 20.0);
    }

    #[test]
    fn segments_are_entered_at_the_near_end() {
        let nodes = segments(&[([10.0, 0.0], [20.0, 0.0]), ([40.0, 0.0], [30.0, 0.0])]);
        let p = Problem {
            start: [0.0, 0.0],
            ret: false,
            nodes: &nodes,
        };
        let r = p.solve(Order::BruteForce);
        assert_eq!(r, vec![(0, 0), (1, 1)]);
        assert_eq!(p.cost(&r), 20.0);
        assert_eq!(p.solve(Order::TwoOpt), r);
        assert_eq!(p.solve(Order::AsGiven), r);
    }

    #[test]
    fn two_opt_never_loses_to_nearest_neighbour_and_brute_force_never_loses_to_either() {
        let mut seed = 7u64;
        for case in 0..200 {
            let n = 1 + case % 7;
            let ss: Vec<(Point, Point)> = (0..n)
                .map(|_| {
                    let a = [lcg(&mut seed) * 100.0, lcg(&mut seed) * 100.0];
                    let b = [a[0] + lcg(&mut seed) * 20.0, a[1] + lcg(&mut seed) * 20.0];
                    (a, b)
                })
                .collect();
            let nodes = segments(&ss);
            orders_hold(&nodes, case);
        }
    }

    /// With and without the return to the start: 2-opt never loses to nearest neighbour, brute
    /// force never loses to 2-opt, and every order visits every node once.
    fn orders_hold(nodes: &[Vec<Ends>], case: usize) {
        for ret in [false, true] {
            let p = Problem {
                start: [0.0, 0.0],
                ret,
                nodes,
            };
            let nn = p.cost(&p.solve(Order::NearestNeighbour));
            let two = p.cost(&p.solve(Order::TwoOpt));
            let bf = p.cost(&p.solve(Order::BruteForce));
            assert!(two <= nn + 1e-9, "{case}: {two} > {nn}");
            assert!(bf <= two + 1e-9, "{case}: {bf} > {two}");
            for o in [
                Order::AsGiven,
                Order::NearestNeighbour,
                Order::TwoOpt,
                Order::BruteForce,
            ] {
                let mut seen: Vec<usize> = p.solve(o).iter().map(|x| x.0).collect();
                seen.sort_unstable();
                assert_eq!(seen, (0..nodes.len()).collect::<Vec<_>>());
            }
        }
    }

    #[test]
    fn empty_and_single() {
        let nodes: Vec<Vec<Ends>> = Vec::new();
        let p = Problem {
            start: [0.0, 0.0],
            ret: true,
            nodes: &nodes,
        };
        for o in [
            Order::AsGiven,
            Order::NearestNeighbour,
            Order::TwoOpt,
            Order::BruteForce,
        ] {
            assert!(p.solve(o).is_empty());
        }
        let nodes = points(&[[3.0, 4.0]]);
        let p = Problem {
            start: [0.0, 0.0],
            ret: true,
            nodes: &nodes,
        };
        assert_eq!(p.cost(&p.solve(Order::TwoOpt)), 10.0);
    }
}
