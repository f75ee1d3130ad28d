//! The memory budget of a render, checked before its buffers are allocated: an estimate of
//! its largest buffers (film, paths in flight, a frame's outputs, light vertex caches, hash
//! grids) against the memory this process may still allocate. A render over budget is an
//! error that names the estimate and the setting that makes it too large, where allocating
//! would abort the process or bring the out-of-memory killer.

use std::fmt;

use thiserror::Error;
use vcm_scheduler::Scheduler;

use crate::integrator::Schedule;

/// A setting that a render's memory grows with, named when the budget is exceeded so that
/// the user knows what to lower.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryCause {
    /// The image size: the film and every per-pixel buffer grow with the pixel count.
    ImageSize,
    /// The samples per pixel each frame renders: each has its own paths, outputs, light
    /// vertex cache and hash grid.
    SamplesPerFrame,
    /// The light vertices each camera vertex connects to: a shadow ray each, held with its
    /// path.
    Connections,
    /// The paths the scheduler keeps in flight (one batch over the whole image, large
    /// tiles, many queues).
    Scheduler,
}

/// The estimated bytes of a render's largest buffers, part by part. An estimate, not an
/// account: smaller buffers (the scene, the BVH, scratch lists) are left out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// (what, bytes) of each part.
    pub parts: Vec<(&'static str, u64)>,
}

impl MemoryEstimate {
    /// This estimate with the part `what` of `bytes` added.
    pub fn with(mut self, what: &'static str, bytes: u64) -> MemoryEstimate {
        self.parts.push((what, bytes));
        self
    }

    /// The bytes of all parts.
    pub fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |total, &(_, bytes)| total.saturating_add(bytes))
    }
}

impl fmt::Display for MemoryEstimate {
    /// The parts that are not empty, largest first: "film 12.0 GiB, paths in flight …".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts: Vec<_> = self.parts.iter().filter(|(_, b)| *b > 0).collect();
        parts.sort_by_key(|&&(_, bytes)| std::cmp::Reverse(bytes));
        for (i, (what, bytes)) in parts.into_iter().enumerate() {
            let separator = if i == 0 { "" } else { ", " };
            write!(f, "{separator}{what} {}", Bytes(*bytes))?;
        }
        Ok(())
    }
}

/// Bytes, printed in the largest binary unit that keeps them at or above 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
        let mut value = self.0 as f64;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < UNITS.len() {
            value /= 1024.0;
            unit += 1;
        }
        if unit == 0 {
            write!(f, "{} bytes", self.0)
        } else {
            write!(f, "{value:.1} {}", UNITS[unit])
        }
    }
}

/// Memory this process may still allocate, and the limit that says so.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AvailableMemory {
    /// Bytes left.
    pub bytes: u64,
    /// Where the figure comes from: `MemAvailable` (/proc/meminfo), `RLIMIT_AS` (the room
    /// left in the address space limit) or `the cgroup's memory limit`.
    pub limit: &'static str,
}

impl AvailableMemory {
    /// The least of the machine's available memory (`MemAvailable`), the room left under
    /// the process's address space limit (`RLIMIT_AS`, less its current virtual size) and
    /// the room left under its cgroup's memory limit (v2 `memory.max`, v1
    /// `memory.limit_in_bytes`). `None` where none can be read (other systems than Linux):
    /// renders are then not checked.
    pub fn of_this_process() -> Option<AvailableMemory> {
        #[cfg(target_os = "linux")]
        {
            [
                linux::mem_available(),
                linux::address_space_room(),
                linux::cgroup_room(),
            ]
            .into_iter()
            .flatten()
            .min_by_key(|available| available.bytes)
        }
        #[cfg(not(target_os = "linux"))]
        None
    }
}

/// A render whose estimated memory exceeds what is available.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error(
    "the render needs about {} ({estimate}), more than the {} available ({}){}",
    Bytes(estimate.total()),
    Bytes(available.bytes),
    available.limit,
    held_already(*held)
)]
pub struct MemoryShortfall {
    /// The render's estimated memory.
    pub estimate: MemoryEstimate,
    /// What was available.
    pub available: AvailableMemory,
    /// Bytes of the estimate the render has allocated already (a frame of another schedule
    /// and its film, which a new one reuses): they need no room of their own.
    pub held: u64,
    /// The setting to lower: the first of the samples per frame, the connections and the
    /// scheduler whose default would bring the estimate within the budget, else the image
    /// size.
    pub cause: MemoryCause,
}

/// " and the … it holds already", for the bytes a render holds (nothing for none).
fn held_already(held: u64) -> String {
    if held == 0 {
        String::new()
    } else {
        format!(" and the {} it holds already", Bytes(held))
    }
}

/// Checks the estimate `estimate` gives for the settings asked for (`estimate(None)`)
/// against `available` (`None`: nothing to check against) and the `held` bytes the render
/// holds already. Over budget, the cause is the first setting whose default alone
/// (`estimate(Some(cause))`, `None` where the setting is at its default already) would fit.
pub fn check_budget(
    estimate: impl Fn(Option<MemoryCause>) -> Option<MemoryEstimate>,
    available: Option<AvailableMemory>,
    held: u64,
) -> Result<(), MemoryShortfall> {
    let (Some(available), Some(asked)) = (available, estimate(None)) else {
        return Ok(());
    };
    let budget = available.bytes.saturating_add(held);
    if asked.total() <= budget {
        return Ok(());
    }
    let fits = |cause| estimate(Some(cause)).is_some_and(|e| e.total() <= budget);
    let cause = [
        MemoryCause::SamplesPerFrame,
        MemoryCause::Connections,
        MemoryCause::Scheduler,
    ]
    .into_iter()
    .find(|&cause| fits(cause))
    .unwrap_or(MemoryCause::ImageSize);
    Err(MemoryShortfall {
        estimate: asked,
        available,
        held,
        cause,
    })
}

/// Checks a render's memory with `schedule` and `connections` per camera vertex (1 for
/// integrators without connections) against what this process may allocate; `estimate`
/// gives the bytes for any schedule and connections. `current` is the schedule of a frame
/// rendered already (`None` before the first): its buffers and film were allocated, so only
/// the growth beyond them needs room.
pub(crate) fn check_render(
    schedule: Schedule,
    connections: u32,
    current: Option<Schedule>,
    estimate: impl Fn(Schedule, u32) -> MemoryEstimate,
) -> Result<(), MemoryShortfall> {
    let held = current.map_or(0, |current| estimate(current, connections).total());
    let at_default = |cause| {
        let (mut schedule, mut connections) = (schedule, connections);
        match cause {
            None => {}
            Some(MemoryCause::SamplesPerFrame) if schedule.samples_per_frame > 1 => {
                schedule.samples_per_frame = 1;
            }
            Some(MemoryCause::Connections) if connections > 1 => connections = 1,
            Some(MemoryCause::Scheduler) if schedule.scheduler != Scheduler::default() => {
                schedule.scheduler = Scheduler::default();
            }
            Some(_) => return None,
        }
        Some(estimate(schedule, connections))
    };
    check_budget(at_default, AvailableMemory::of_this_process(), held)
}

/// Bytes of `count` values of `T`, saturating.
pub(crate) fn bytes_of<T>(count: u64) -> u64 {
    count.saturating_mul(size_of::<T>() as u64)
}

#[cfg(target_os = "linux")]
mod linux {
    use super::AvailableMemory;

    /// `MemAvailable` of /proc/meminfo.
    pub fn mem_available() -> Option<AvailableMemory> {
        let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
        let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(AvailableMemory {
            bytes: kib.saturating_mul(1024),
            limit: "MemAvailable",
        })
    }

    /// The soft `RLIMIT_AS` less the process's virtual size (/proc/self/statm), if set.
    pub fn address_space_room() -> Option<AvailableMemory> {
        let mut limit = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit only writes the struct it is given.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } != 0
            || limit.rlim_cur == libc::RLIM_INFINITY
        {
            return None;
        }
        let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
        let pages: u64 = statm.split_whitespace().next()?.parse().ok()?;
        // SAFETY: sysconf reads a constant of the system.
        let page_size = u64::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) }).ok()?;
        Some(AvailableMemory {
            bytes: limit
                .rlim_cur
                .saturating_sub(pages.saturating_mul(page_size)),
            limit: "RLIMIT_AS",
        })
    }

    /// The room left under the memory limit of the process's cgroup, if it has one.
    pub fn cgroup_room() -> Option<AvailableMemory> {
        let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
        room_under_cgroup(&groups, "/sys/fs/cgroup")
    }

    /// The room left under the memory limit of the cgroup that `groups` (the text of
    /// /proc/self/cgroup) names, its file systems mounted at `root`.
    pub(super) fn room_under_cgroup(groups: &str, root: &str) -> Option<AvailableMemory> {
        groups.lines().find_map(|line| {
            // "0::/path" (v2) or "4:memory:/path" (v1).
            let mut fields = line.splitn(3, ':');
            let (_, controllers, path) = (fields.next()?, fields.next()?, fields.next()?);
            let (folder, max, current) = match controllers {
                "" => (format!("{root}{path}"), "memory.max", "memory.current"),
                "memory" => (
                    format!("{root}/memory{path}"),
                    "memory.limit_in_bytes",
                    "memory.usage_in_bytes",
                ),
                _ => return None,
            };
            let read = |file: &str| -> Option<u64> {
                std::fs::read_to_string(format!("{folder}/{file}"))
                    .ok()?
                    .trim()
                    .parse()
                    .ok()
            };
            // "max" (v2) does not parse: no limit.
            let max = read(max)?;
            Some(AvailableMemory {
                bytes: max.saturating_sub(read(current)?),
                limit: "the cgroup's memory limit",
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GIB: u64 = 1 << 30;

    fn available(bytes: u64) -> Option<AvailableMemory> {
        Some(AvailableMemory {
            bytes,
            limit: "test",
        })
    }

    /// A render of `pixels` × 1 KiB per sample per frame plus 1 KiB per connection per pixel.
    fn estimate(
        samples: u64,
        connections: u64,
    ) -> impl Fn(Option<MemoryCause>) -> Option<MemoryEstimate> {
        move |cause| {
            let (samples, connections) = match cause {
                None => (samples, connections),
                Some(MemoryCause::SamplesPerFrame) if samples > 1 => (1, connections),
                Some(MemoryCause::Connections) if connections > 1 => (samples, 1),
                Some(_) => return None,
            };
            Some(
                MemoryEstimate::default()
                    .with("film", GIB)
                    .with("outputs", samples * GIB)
                    .with("shadow rays", connections * GIB),
            )
        }
    }

    #[test]
    fn a_render_within_the_budget_passes() {
        assert_eq!(check_budget(estimate(1, 1), available(3 * GIB), 0), Ok(()));
        // Nothing to check against.
        assert_eq!(check_budget(estimate(100, 100), None, 0), Ok(()));
        // What the render holds already needs no room of its own.
        assert_eq!(
            check_budget(estimate(2, 1), available(GIB), 3 * GIB),
            Ok(())
        );
    }

    #[test]
    fn a_render_over_the_budget_names_the_setting_to_lower() {
        let over = |samples, connections, bytes| {
            check_budget(estimate(samples, connections), available(bytes), 0).unwrap_err()
        };
        let samples = over(100, 1, 4 * GIB);
        assert_eq!(samples.cause, MemoryCause::SamplesPerFrame);
        assert_eq!(samples.estimate.total(), 102 * GIB);
        assert_eq!(over(1, 100, 4 * GIB).cause, MemoryCause::Connections);
        // Neither default alone fits: the image size is what is left to lower.
        assert_eq!(over(100, 100, 4 * GIB).cause, MemoryCause::ImageSize);
        assert_eq!(over(1, 1, 2 * GIB).cause, MemoryCause::ImageSize);
        let held = check_budget(estimate(100, 1), available(GIB), 3 * GIB).unwrap_err();
        assert_eq!(held.cause, MemoryCause::SamplesPerFrame);
        assert!(
            held.to_string()
                .ends_with("available (test) and the 3.0 GiB it holds already"),
            "{held}"
        );
        assert_eq!(
            over(100, 1, 4 * GIB).to_string(),
            "the render needs about 102.0 GiB (outputs 100.0 GiB, film 1.0 GiB, shadow rays \
             1.0 GiB), more than the 4.0 GiB available (test)"
        );
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn a_cgroup_limit_leaves_the_room_under_it_in_v2_and_v1() {
        let root = tempfile::tempdir().unwrap();
        let write = |folder: &str, file: &str, text: &str| {
            let folder = root.path().join(folder);
            std::fs::create_dir_all(&folder).unwrap();
            std::fs::write(folder.join(file), text).unwrap();
        };
        write("jobs/render", "memory.max", "4294967296\n");
        write("jobs/render", "memory.current", "1073741824\n");
        write("memory/old", "memory.limit_in_bytes", "2147483648\n");
        write("memory/old", "memory.usage_in_bytes", "536870912\n");
        write("free", "memory.max", "max\n");
        write("free", "memory.current", "1073741824\n");
        let root = root.path().to_str().unwrap();
        let room = |groups: &str| linux::room_under_cgroup(groups, root).map(|room| room.bytes);
        assert_eq!(room("0::/jobs/render\n"), Some(3 * GIB), "v2");
        assert_eq!(
            room("12:cpu:/x\n4:memory:/old\n"),
            Some(GIB + GIB / 2),
            "v1"
        );
        assert_eq!(room("0::/free\n"), None, "no limit");
        assert_eq!(room("0::/missing\n"), None, "no such group");
        write("jobs/over", "memory.max", "1073741824");
        write("jobs/over", "memory.current", "2147483648");
        assert_eq!(room("0::/jobs/over"), Some(0), "over its limit already");
    }

    #[test]
    fn bytes_print_in_binary_units() {
        assert_eq!(Bytes(17).to_string(), "17 bytes");
        assert_eq!(Bytes(1536).to_string(), "1.5 KiB");
        assert_eq!(Bytes(3 * GIB).to_string(), "3.0 GiB");
        assert_eq!(
            MemoryEstimate::default()
                .with("a", u64::MAX)
                .with("b", 1)
                .total(),
            u64::MAX
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn this_process_has_some_memory_left() {
        let available = AvailableMemory::of_this_process().expect("/proc/meminfo is readable");
        assert!(available.bytes > 0, "{available:?}");
    }
}
