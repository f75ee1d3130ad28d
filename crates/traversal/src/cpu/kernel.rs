//! Traversal of the 8-wide hierarchy for closest-hit and any-hit searches: one ray at a
//! time ([`search`]), or several rays in turn ([`search_in_turn`]), a step at a time in the
//! same order.
//!
//! A step is one node test or the triangle tests of one node's hit leaves. A node's leaves
//! are tested before its children are entered, and the children nearest along the ray are
//! entered first, so that closest-hit searches shrink their interval early and skip the
//! children that lie beyond their closest hit.
//!
//! On a hierarchy far larger than the caches, most of a step's time goes to waiting for its
//! node or triangles to arrive from memory; taking [`LANES_LARGE`] rays in turn, each step
//! prefetches what its ray's next step reads, so that those misses overlap the other rays'
//! work. Where everything stays in cache the single-ray loop is faster (fewer branches per
//! step).

use super::filter::HitFilter;
use super::geometry::LeafGeometry;
use super::node::{NodeHits, NodeTest, widen_up};
use super::ray::PreparedRay;
use super::triangle::{Candidate, LeafGroup, TriangleTest};
use super::wide_node::WideNode;

/// Rays traced in turn per thread on hierarchies larger than the caches.
pub(crate) const LANES_LARGE: usize = 8;

/// What a ray's traversal does next.
#[derive(Clone, Copy)]
enum Step {
    /// Test the ray against node `index`.
    Node(u32),
    /// Test the leaf triangles of a node.
    Leaves(LeafGroup),
    /// Nothing is left to visit.
    Done,
}

/// One ray's place in the hierarchy, with a stack as deep as the hierarchy needs. Reused
/// across the rays of a chunk.
pub(crate) struct Walk {
    /// The node to visit next, with a lower bound of the ray parameter at which the ray
    /// enters it: the only child the last node test hit, or the root. Kept off the stack,
    /// since most nodes of a small hierarchy send a ray into one child or none.
    only_child: Option<(u32, f32)>,
    /// Nodes still to visit after it, with the same bounds; in decreasing order of the bound
    /// within each node's children, so the nearest is on top.
    stack: NodeStack,
    /// Leaf triangles still to test (none: an empty mask).
    leaves: LeafGroup,
}

impl Walk {
    /// A walk able to traverse `geometry`.
    pub fn new(geometry: &LeafGeometry) -> Self {
        Self {
            only_child: None,
            stack: NodeStack::new(geometry.levels),
            leaves: LeafGroup::default(),
        }
    }

    /// Starts over at the root.
    #[inline(always)]
    fn start(&mut self, geometry: &LeafGeometry) {
        self.stack.clear();
        self.only_child = (!geometry.nodes.is_empty()).then_some((0, f32::NEG_INFINITY));
        self.leaves.mask = 0;
    }

    /// The next step of a search that has nothing to find beyond `tmax`: the leaves of the
    /// node visited last, else the nearest node left that the ray may enter by `tmax`.
    #[inline(always)]
    fn next(&mut self, tmax: f32) -> Step {
        if self.leaves.mask != 0 {
            return Step::Leaves(std::mem::take(&mut self.leaves));
        }
        let bound = widen_up(tmax);
        if let Some((node, entry)) = self.only_child.take()
            && entry <= bound
        {
            return Step::Node(node);
        }
        while let Some((node, entry)) = self.stack.pop() {
            if entry <= bound {
                return Step::Node(node);
            }
        }
        Step::Done
    }

    /// Takes in what the ray overlaps among `node`'s children.
    #[inline(always)]
    fn visited(&mut self, node: &WideNode, hits: &NodeHits) {
        self.leaves = LeafGroup {
            first: node.first_triangle as usize,
            count: node.triangle_count as usize,
            mask: hits.leaves,
        };
        let mut inner = hits.inner;
        if inner & inner.wrapping_sub(1) == 0 {
            let slot = inner.trailing_zeros() as usize;
            self.only_child = (inner != 0).then(|| (node.children[slot], hits.entry[slot]));
            return;
        }
        let base = self.stack.len;
        while inner != 0 {
            let slot = inner.trailing_zeros() as usize;
            inner &= inner - 1;
            self.stack
                .insert_above(base, (node.children[slot], hits.entry[slot]));
        }
    }
}

/// A stack of nodes to visit with their entry bounds, as deep as a hierarchy of `levels`
/// needs: each level pops one node and pushes at most eight children.
struct NodeStack {
    entries: Box<[(u32, f32)]>,
    len: usize,
}

impl NodeStack {
    fn new(levels: usize) -> Self {
        Self {
            entries: vec![(0, 0.0); 7 * levels + 1].into_boxed_slice(),
            len: 0,
        }
    }

    #[inline(always)]
    fn clear(&mut self) {
        self.len = 0;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        self.len = self.len.checked_sub(1)?;
        Some(self.entries[self.len])
    }

    /// Pushes `entry` among the entries from `base` up, which stay in decreasing order of
    /// their bounds (an insertion sort).
    #[inline(always)]
    fn insert_above(&mut self, base: usize, entry: (u32, f32)) {
        let mut at = self.len;
        self.len += 1;
        while at > base && self.entries[at - 1].1 < entry.1 {
            self.entries[at] = self.entries[at - 1];
            at -= 1;
        }
        self.entries[at] = entry;
    }
}

/// Asks for the memory `step` reads.
#[inline(always)]
fn prefetch(geometry: &LeafGeometry, step: Step) {
    match step {
        Step::Node(index) => geometry.prefetch_node(index as usize),
        Step::Leaves(group) => geometry.triangles.prefetch(&group),
        Step::Done => {}
    }
}

/// A search along a ray: the upper bound of t for its node tests (shrinking as closer hits
/// are found) and what it has found, `T`.
pub(crate) struct Found<T> {
    tmax: f32,
    /// What was found.
    pub hit: T,
}

impl<T: Default> Found<T> {
    /// A search along `ray`, nothing found yet.
    #[inline(always)]
    fn new(ray: &PreparedRay) -> Self {
        Self {
            tmax: ray.tmax,
            hit: T::default(),
        }
    }
}

/// The closest accepted intersection in `[ray.tmin, ray.tmax)`: the leaf index of its
/// triangle and the intersection.
pub(crate) type ClosestHit = Found<Option<(usize, Candidate)>>;

/// Whether any accepted intersection lies in `[ray.tmin, ray.tmax)`; stops at the first.
pub(crate) type AnyHit = Found<bool>;

/// How a search takes in a node's leaves.
pub(crate) trait Search {
    /// Tests the triangles of `group` its mask selects; returns true when the search is
    /// over.
    fn leaves<N: TriangleTest, F: HitFilter>(
        &mut self,
        geometry: &LeafGeometry,
        node_test: N,
        filter: &F,
        ray: &PreparedRay,
        group: LeafGroup,
    ) -> bool;
}

impl ClosestHit {
    /// The bound a candidate's t must stay under: once something is hit, a candidate at
    /// exactly the same t wins only with a smaller id, so ties resolve the same way whatever
    /// the traversal order.
    #[inline(always)]
    fn limit(&self) -> f32 {
        match self.hit {
            Some(_) => self.tmax.next_up(),
            None => self.tmax,
        }
    }
}

impl Search for ClosestHit {
    #[inline(always)]
    fn leaves<N: TriangleTest, F: HitFilter>(
        &mut self,
        geometry: &LeafGeometry,
        node_test: N,
        filter: &F,
        ray: &PreparedRay,
        group: LeafGroup,
    ) -> bool {
        let limit = self.limit();
        node_test.candidates(&geometry.triangles, ray, group, limit, |leaf, c| {
            // The limit only shrinks while the group's candidates are taken in turn.
            if c.t < self.limit()
                && self.hit.is_none_or(|(best, _)| {
                    c.t < self.tmax || geometry.ids[leaf] < geometry.ids[best]
                })
                && filter.accepts(leaf, &c)
            {
                self.tmax = c.t;
                self.hit = Some((leaf, c));
            }
            false
        });
        false
    }
}

impl Search for AnyHit {
    #[inline(always)]
    fn leaves<N: TriangleTest, F: HitFilter>(
        &mut self,
        geometry: &LeafGeometry,
        node_test: N,
        filter: &F,
        ray: &PreparedRay,
        group: LeafGroup,
    ) -> bool {
        let accept = |leaf, candidate| filter.accepts(leaf, &candidate);
        self.hit = node_test.candidates(&geometry.triangles, ray, group, self.tmax, accept);
        self.hit
    }
}

/// Takes `step` of `search` along `ray`; returns true when the search is over.
#[inline(always)]
fn take_step<T, N: NodeTest + TriangleTest, F: HitFilter>(
    (geometry, node_test, filter): (&LeafGeometry, N, &F),
    walk: &mut Walk,
    ray: &PreparedRay,
    search: &mut Found<T>,
    step: Step,
) -> bool
where
    Found<T>: Search,
{
    match step {
        Step::Node(index) => {
            let node = &geometry.nodes[index as usize];
            walk.visited(node, &node_test.intersect(node, ray, search.tmax));
            false
        }
        Step::Leaves(group) => search.leaves(geometry, node_test, filter, ray, group),
        Step::Done => true,
    }
}

/// Runs the search for `T` along `ray`, reusing `walk`.
#[inline(always)]
pub(crate) fn search<T: Default, N: NodeTest + TriangleTest, F: HitFilter>(
    geometry: &LeafGeometry,
    node_test: N,
    filter: &F,
    walk: &mut Walk,
    ray: &PreparedRay,
) -> Found<T>
where
    Found<T>: Search,
{
    walk.start(geometry);
    let mut search = Found::new(ray);
    loop {
        let step = walk.next(search.tmax);
        if take_step((geometry, node_test, filter), walk, ray, &mut search, step) {
            return search;
        }
    }
}

/// A ray in flight: its index in the chunk, the ray, its search and its next step.
struct Lane<T> {
    walk: Walk,
    flight: Option<(usize, PreparedRay, Found<T>)>,
    step: Step,
}

/// Runs the search for `T` for rays `0..count` of a chunk (`ray(i)`; `None`: a ray that
/// cannot hit anything), `LANES` of them in turn, handing each result to `done(i, search)`
/// (`None` for the rays that could not hit anything).
#[inline(always)]
pub(crate) fn search_in_turn<
    T: Default,
    N: NodeTest + TriangleTest,
    F: HitFilter,
    const LANES: usize,
>(
    geometry: &LeafGeometry,
    node_test: N,
    filter: &F,
    (count, ray): (usize, impl Fn(usize) -> Option<PreparedRay>),
    mut done: impl FnMut(usize, Option<Found<T>>),
) where
    Found<T>: Search,
{
    let mut next = 0;
    // Gives `lane` the next ray that can hit anything; false when none is left.
    let mut refill = |lane: &mut Lane<T>, done: &mut dyn FnMut(usize, Option<Found<T>>)| {
        while next < count {
            let index = next;
            next += 1;
            if let Some(ray) = ray(index) {
                lane.walk.start(geometry);
                lane.step = lane.walk.next(ray.tmax);
                lane.flight = Some((index, ray, Found::new(&ray)));
                return true;
            }
            done(index, None);
        }
        lane.flight = None;
        false
    };
    let mut lanes: [Lane<T>; LANES] = std::array::from_fn(|_| Lane {
        walk: Walk::new(geometry),
        flight: None,
        step: Step::Done,
    });
    let mut active = 0;
    for lane in &mut lanes {
        active += usize::from(refill(lane, &mut done));
    }
    while active > 0 {
        for lane in &mut lanes {
            let Some((_, ray, search)) = &mut lane.flight else {
                continue;
            };
            let finished = take_step(
                (geometry, node_test, filter),
                &mut lane.walk,
                ray,
                search,
                lane.step,
            );
            if finished {
                let (index, _, search) = lane.flight.take().expect("the lane is in flight");
                done(index, Some(search));
                if !refill(lane, &mut done) {
                    active -= 1;
                    continue;
                }
            } else {
                lane.step = lane.walk.next(search.tmax);
            }
            prefetch(geometry, lane.step);
        }
    }
}
