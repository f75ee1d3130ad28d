//! Backing large arrays that are read at random with huge pages.
//!
//! The light vertex cache is tens of megabytes read at random by connections and merges:
//! with 4 KiB pages nearly every such read also misses the TLB and waits for a page walk.
//! Linux backs a region with 2 MiB pages where it is asked to (`MADV_HUGEPAGE`, for the
//! usual `madvise` setting of transparent huge pages), so that the whole cache needs a few
//! dozen TLB entries. A hint only: the contents and results do not change, and elsewhere it
//! does nothing.

/// Size of a huge page on the platforms the hint is given on.
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// Asks the OS to back the whole 2 MiB pages inside `buffer`'s allocation (its capacity)
/// with huge pages. Call it before the memory is first written: pages already touched keep
/// their size until the kernel merges them later.
pub(crate) fn advise_huge_pages<T>(buffer: &mut Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        let start = buffer.as_mut_ptr() as usize;
        let end = start + buffer.capacity() * size_of::<T>();
        let (first, last) = (
            start.next_multiple_of(HUGE_PAGE),
            end / HUGE_PAGE * HUGE_PAGE,
        );
        if last > first {
            // SAFETY: [first, last) lies inside the vector's allocation, which it owns;
            // MADV_HUGEPAGE changes how the kernel backs the range, never its contents.
            // A failure (a kernel without transparent huge pages) leaves the pages as they are.
            unsafe {
                libc::madvise(
                    first as *mut libc::c_void,
                    last - first,
                    libc::MADV_HUGEPAGE,
                );
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = buffer;
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// The `VmFlags` of the mapping that holds `address`, from `/proc/self/smaps`.
    fn vm_flags(address: usize) -> Option<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut holds = false;
        for line in smaps.lines() {
            let range = line
                .split_whitespace()
                .next()
                .and_then(|r| r.split_once('-'));
            if let Some((start, end)) = range
                && let (Ok(start), Ok(end)) = (
                    usize::from_str_radix(start, 16),
                    usize::from_str_radix(end, 16),
                )
            {
                holds = (start..end).contains(&address);
            } else if holds && let Some(flags) = line.strip_prefix("VmFlags:") {
                return Some(flags.to_string());
            }
        }
        None
    }

    /// The kernel records the advice on the buffer's memory: its mapping carries the `hg`
    /// (huge pages advised) flag. Kernels built without transparent huge pages reject the
    /// advice, so the check runs only where they exist.
    #[test]
    fn a_large_buffer_is_advised_to_use_huge_pages() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage").exists() {
            return;
        }
        let mut buffer: Vec<u8> = Vec::with_capacity(4 * HUGE_PAGE);
        advise_huge_pages(&mut buffer);
        let middle = buffer.as_ptr() as usize + 2 * HUGE_PAGE;
        let flags = vm_flags(middle).expect("the buffer is mapped");
        assert!(
            flags.split_whitespace().any(|flag| flag == "hg"),
            "flags: {flags}"
        );
    }
}
