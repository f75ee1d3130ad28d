//! CWBVH traversal for closest-hit and any-hit searches: one ray at a time with obvhs's
//! `traverse!` loop ([`search`]), or several rays in turn ([`search_in_turn`]), a step at a
//! time in the same order.
//!
//! A step is one node test or the triangle tests of one node's leaves. On a hierarchy far
//! larger than the caches, most of a step's time goes to waiting for its node or triangles
//! to arrive from memory; taking [`LANES_LARGE`] rays in turn, each step prefetches what
//! its ray's next step reads, so that those misses overlap the other rays' work. Where
//! everything stays in cache the single-ray loop is faster (fewer branches per step).

use glam::UVec2;
use obvhs::cwbvh::firstbithigh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::faststack::{FastStack, HeapStack};

use super::filter::HitFilter;
use super::geometry::LeafGeometry;
use super::node::NodeTest;
use super::ray::PreparedRay;
use super::triangle::{Candidate, TriangleTest};

/// Rays traced in turn per thread on hierarchies larger than the caches.
pub(crate) const LANES_LARGE: usize = 8;

/// A node group holding just the root: one hit bit in the top byte, which resolves to
/// relative index 0 (node 0) whatever the ray's octant.
const ROOT_GROUP: UVec2 = UVec2::new(0, 0x8000_0000);

/// What a ray's traversal does next.
#[derive(Clone, Copy)]
enum Step {
    /// Test the ray against node `index`.
    Node(u32),
    /// Test leaf triangles `first + k` for the set bits `k` of `mask`.
    Leaves { first: usize, mask: u32 },
    /// Nothing is left to visit.
    Done,
}

/// One ray's place in the hierarchy, with the fields `traverse!` uses and a stack as deep
/// as the hierarchy (obvhs's own traversal state has a fixed 32-entry stack that degenerate
/// inputs can overflow). Reused across the rays of a chunk.
pub(crate) struct Walk {
    stack: HeapStack<UVec2>,
    /// Node children still to visit: base index, hit bits in the top byte, internal-child
    /// mask in the low byte.
    current_group: UVec2,
    /// Leaf triangles still to test: first index, a bit per triangle.
    primitive_group: UVec2,
    oct_inv4: u32,
    /// The leaf `traverse!` took last.
    primitive_id: u32,
    /// The last node test's hit mask (`traverse!`'s scratch).
    hitmask: u32,
}

impl Walk {
    /// A walk able to traverse `geometry`.
    pub fn new(geometry: &LeafGeometry) -> Self {
        Self {
            stack: HeapStack::new_with_capacity(geometry.levels.max(1)),
            current_group: UVec2::ZERO,
            primitive_group: UVec2::ZERO,
            oct_inv4: 0,
            primitive_id: 0,
            hitmask: 0,
        }
    }

    /// The primitives left in the node's group, including the one `traverse!` just took: the
    /// first leaf index and a bit per leaf after it. Empties the group, so that `traverse!`
    /// goes on to the next node once they are all tested together.
    #[inline(always)]
    fn take_primitive_group(&mut self) -> (usize, u32) {
        let first = self.primitive_group.x;
        let mask = self.primitive_group.y | (1 << (self.primitive_id - first));
        self.primitive_group.y = 0;
        (first as usize, mask)
    }

    /// Starts over at the root for `ray`.
    #[inline(always)]
    fn start(&mut self, geometry: &LeafGeometry, ray: &PreparedRay) {
        self.stack.clear();
        self.current_group = if geometry.bvh.nodes.is_empty() {
            UVec2::ZERO
        } else {
            ROOT_GROUP
        };
        self.primitive_group = UVec2::ZERO;
        self.oct_inv4 = ray.oct_inv4;
    }

    /// The next step: the leaves of the node visited last, else the next child in the
    /// current group, else the group on top of the stack.
    #[inline(always)]
    fn next(&mut self) -> Step {
        loop {
            if self.primitive_group.y != 0 {
                let UVec2 { x: first, y: mask } = self.primitive_group;
                self.primitive_group = UVec2::ZERO;
                return Step::Leaves {
                    first: first as usize,
                    mask,
                };
            }
            let hits = self.current_group.y;
            if hits & 0xff00_0000 != 0 {
                let offset = firstbithigh(hits);
                self.current_group.y &= !(1 << offset);
                if self.current_group.y & 0xff00_0000 != 0 {
                    self.stack.push(self.current_group);
                }
                // The child's slot in the node, and the internal children stored before it.
                let slot = (offset - 24) ^ (self.oct_inv4 & 0xff);
                let relative = (hits & !(u32::MAX << slot)).count_ones();
                return Step::Node(self.current_group.x + relative);
            }
            if self.stack.is_empty() {
                return Step::Done;
            }
            self.current_group = self.stack.pop_fast();
        }
    }

    /// Takes in the node test's hit mask for `node`.
    #[inline(always)]
    fn visited(&mut self, node: &CwBvhNode, hitmask: u32) {
        self.current_group = UVec2::new(
            node.child_base_idx,
            (hitmask & 0xff00_0000) | u32::from(node.imask),
        );
        self.primitive_group = UVec2::new(node.primitive_base_idx, hitmask & 0x00ff_ffff);
    }
}

/// Asks for the memory `step` reads.
#[inline(always)]
fn prefetch(geometry: &LeafGeometry, step: Step) {
    match step {
        Step::Node(index) => geometry.prefetch_node(index as usize),
        Step::Leaves { first, mask } => {
            geometry
                .triangles
                .prefetch(first + mask.trailing_zeros() as usize);
        }
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
    /// Tests the leaf triangles `first + k` for the set bits `k` of `mask` (`group`); returns
    /// true when the search is over.
    fn leaves<N: TriangleTest, F: HitFilter>(
        &mut self,
        geometry: &LeafGeometry,
        node_test: N,
        filter: &F,
        ray: &PreparedRay,
        group: (usize, u32),
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
        (first, mask): (usize, u32),
    ) -> bool {
        let limit = self.limit();
        node_test.candidates(&geometry.triangles, ray, first, mask, limit, |leaf, c| {
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
        (first, mask): (usize, u32),
    ) -> bool {
        let accept = |leaf, candidate| filter.accepts(leaf, &candidate);
        self.hit = node_test.candidates(&geometry.triangles, ray, first, mask, self.tmax, accept);
        self.hit
    }
}

/// Runs the search for `T` along `ray` with obvhs's `traverse!` loop, reusing `walk`.
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
    let bvh = &geometry.bvh;
    walk.start(geometry, ray);
    let mut search = Found::new(ray);
    let mut node;
    'search: {
        obvhs::traverse!(
            bvh,
            node,
            walk,
            node_test.intersect(node, ray, walk.oct_inv4, search.tmax),
            {
                let group = walk.take_primitive_group();
                if search.leaves(geometry, node_test, filter, ray, group) {
                    break 'search;
                }
            }
        );
    }
    search
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
                lane.walk.start(geometry, &ray);
                lane.step = lane.walk.next();
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
            let finished = match lane.step {
                Step::Node(node) => {
                    let node = &geometry.bvh.nodes[node as usize];
                    let oct_inv4 = lane.walk.oct_inv4;
                    let hitmask = node_test.intersect(node, ray, oct_inv4, search.tmax);
                    lane.walk.visited(node, hitmask);
                    false
                }
                Step::Leaves { first, mask } => {
                    search.leaves(geometry, node_test, filter, ray, (first, mask))
                }
                Step::Done => true,
            };
            if finished {
                let (index, _, search) = lane.flight.take().expect("the lane is in flight");
                done(index, Some(search));
                if !refill(lane, &mut done) {
                    active -= 1;
                    continue;
                }
            } else {
                lane.step = lane.walk.next();
            }
            prefetch(geometry, lane.step);
        }
    }
}
