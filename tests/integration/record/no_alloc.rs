//! `RecordTx::push` allocates nothing, whether the ring takes the item or is full: a
//! counting global allocator watches the pushing thread (the writer thread allocates
//! on its own, and is not counted).

use crate::support::counting_alloc;
use crate::support::record_fixture as fixture;

use counting_alloc::allocator_calls;
use fixture::*;
use snaked::record::{RecordOptions, start};

#[test]
fn push_allocates_nothing_when_accepted_or_dropped() {
    let (catalog, id) = catalog();
    let opts = RecordOptions {
        ring_capacity: 8,
        ..RecordOptions::default()
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    // Built before counting: the items themselves are plain stack values.
    let items = run(400, id, true);
    assert!(
        allocator_calls(|| drop(std::hint::black_box(vec![1u8; 8]))) >= 2,
        "the counter counts"
    );
    let (mut accepted, mut pushes) = (0u64, 0u64);
    let n = allocator_calls(|| {
        // An 8-item ring fills long before the writer (polling every 2 ms) drains it:
        // push until both paths have run (bounded).
        for item in items.iter().cycle().take(1_000_000) {
            pushes += 1;
            if tx.push(item) {
                accepted += 1;
            }
            if tx.dropped() >= 100 {
                break;
            }
        }
    });
    assert_eq!(n, 0, "{n} allocator calls in push");
    assert!(accepted > 0);
    assert!(tx.dropped() >= 100, "the full-ring path ran");
    assert_eq!(accepted + tx.dropped(), pushes);
    rec.finish().expect("finish");
}
