//! How the fluid-node benches run a step: on a thread of rayon's pool, as the fluid node does.

/// Run `f` on a thread of rayon's pool, as the fluid node serves its steps
/// (src/bin/fluid-node.rs): parallel loops then start on a worker instead of handing their
/// work to the pool from outside, which costs two context switches per loop.
pub fn on_pool_thread<R>(f: impl FnOnce() -> R) -> R {
    struct Carry<T>(T);
    // SAFETY: `rayon::scope` blocks this thread until `f` has returned on the pool thread, so
    // what `f` captures (the in-process exchange's `Rc` among it) is used by one thread at a
    // time, with the hand-over and the return ordered by the scope's join.
    unsafe impl<T> Send for Carry<T> {}
    impl<T> Carry<T> {
        fn into_inner(self) -> T {
            self.0
        }
    }
    let f = Carry(f);
    rayon::scope(move |_| Carry(f.into_inner()())).into_inner()
}
