//! Peak-memory measurement: a global allocator that counts live heap bytes and their peak.
//! The `voxlod` binary registers it; library users can too:
//!
//! ```
//! use voxlod_studies::alloc::{self, TrackingAllocator};
//!
//! #[global_allocator]
//! static ALLOC: TrackingAllocator = TrackingAllocator;
//!
//! fn main() {
//!     let (v, peak) = alloc::measure_peak(|| vec![0u8; 1 << 20]);
//!     assert!(alloc::is_active());
//!     assert!(peak.unwrap() >= 1 << 20, "{peak:?}");
//!     drop(v);
//! }
//! ```
//!
//! Where it is not registered, [`is_active`] is false and reports print "n/a".

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::Relaxed};

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static ACTIVE: AtomicBool = AtomicBool::new(false);

/// The system allocator plus two counters (live bytes and their peak). The overhead is two
/// relaxed atomic operations per allocation.
pub struct TrackingAllocator;

#[inline]
fn add(bytes: usize) {
    let now = CURRENT.fetch_add(bytes, Relaxed) + bytes;
    PEAK.fetch_max(now, Relaxed);
}

// SAFETY: every method forwards to `System` with the caller's layout and pointer unchanged; the
// counters do not affect allocation.
unsafe impl GlobalAlloc for TrackingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ACTIVE.store(true, Relaxed);
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            add(layout.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ACTIVE.store(true, Relaxed);
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            add(layout.size());
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) };
        CURRENT.fetch_sub(layout.size(), Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            CURRENT.fetch_sub(layout.size(), Relaxed);
            add(new_size);
        }
        p
    }
}

/// Whether the tracking allocator is registered (has seen an allocation).
pub fn is_active() -> bool {
    ACTIVE.load(Relaxed)
}

/// Live heap bytes now.
pub fn current() -> usize {
    CURRENT.load(Relaxed)
}

/// Peak live heap bytes since the last [`reset_peak`].
pub fn peak() -> usize {
    PEAK.load(Relaxed)
}

/// Restarts peak tracking from the current live bytes.
pub fn reset_peak() {
    PEAK.store(CURRENT.load(Relaxed), Relaxed);
}

/// Runs `f` and returns its result with the most heap bytes it held at once beyond what was
/// live when it started (its own peak footprint: temporaries and its result), or `None` when
/// the tracking allocator is not registered. Not meaningful when several measurements run
/// concurrently.
pub fn measure_peak<T>(f: impl FnOnce() -> T) -> (T, Option<usize>) {
    let before = current();
    reset_peak();
    let out = f();
    (out, is_active().then(|| peak().saturating_sub(before)))
}
