//! [`SnakeEnv::step_into`] makes no Rust heap allocation (Bullet's own C++ allocations are outside
//! Rust's allocator and not counted here; the memory test in `tests/env_memory.rs` covers them).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use snake_core::{EnvConfig, ObservationLayout, ResetOptions, RewardConfig, SnakeEnv};

/// Counts the allocations made on a thread while its flag is set.
struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        System.alloc(layout)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn allocations_in(f: impl FnOnce()) -> usize {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|c| c.set(true));
    f();
    COUNTING.with(|c| c.set(false));
    COUNT.with(Cell::get)
}

#[test]
fn step_into_does_not_allocate() {
    let configs = [
        EnvConfig::snakebot_gym(5),
        EnvConfig {
            observation: ObservationLayout::Extended,
            physics_steps_per_env_step: 3,
            reward: RewardConfig {
                progress_weight: 1.0,
                smoothness_weight: 0.1,
                energy_weight: 0.01,
                ..RewardConfig::default()
            },
            ..EnvConfig::default()
        },
    ];
    for config in configs {
        let mut env = SnakeEnv::new(config).unwrap();
        let mut obs = vec![0.0f32; env.observation_dim()];
        env.reset_into(Some(1), ResetOptions::default(), &mut obs)
            .unwrap();
        let mut action = [0.0f32; 5];
        let count = allocations_in(|| {
            for k in 0..500 {
                for (j, a) in action.iter_mut().enumerate() {
                    *a = ((k * 5 + j) as f32 * 0.3).sin();
                }
                let out = env.step_into(&action, &mut obs).unwrap();
                assert!(!out.terminated && !out.truncated);
            }
        });
        assert_eq!(count, 0, "step_into allocated {count} times in 500 steps");
    }
}
