//! A counting global allocator for the no-allocation and memory tests. Every allocation and
//! reallocation made by the current thread is counted, and the thread's live heap bytes and
//! their peak are tracked: each test measures only its own thread, while the harness and the
//! other tests of the same binary allocate on other threads meanwhile. Declared once per test
//! binary (`tests/main.rs`, `lab/tests/common/mod.rs`), since a binary has one global allocator.

use std::alloc::{GlobalAlloc, Layout, System as SystemAlloc};
use std::cell::Cell;

pub struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    // Signed: a thread may free memory that another thread allocated.
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

/// Record `bytes` more (or fewer) live bytes on this thread; `counted`: one more allocation.
fn record(bytes: isize, counted: bool) {
    // `try_with`: the allocator may run while a thread's locals are being torn down.
    let _ = LIVE.try_with(|live| {
        let now = live.get() + bytes;
        live.set(now);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(now)));
    });
    if counted {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    }
}

/// Allocations made by this thread so far.
pub fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Peak growth of this thread's live heap bytes (above the level at the start) while `f` runs.
/// Exact for work that stays on the calling thread.
#[allow(dead_code)]
pub fn peak_during(f: impl FnOnce()) -> usize {
    let base = LIVE.with(Cell::get);
    PEAK.with(|peak| peak.set(base));
    f();
    (PEAK.with(Cell::get) - base).max(0) as usize
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { SystemAlloc.alloc(layout) };
        if !p.is_null() {
            record(layout.size() as isize, true);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { SystemAlloc.dealloc(ptr, layout) };
        record(-(layout.size() as isize), false);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { SystemAlloc.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            record(new_size as isize - layout.size() as isize, true);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;
