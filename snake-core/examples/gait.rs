//! The lateral-undulation gait on a 10-joint snake for 5 simulated seconds.
//!
//! Run with `cargo run --release -p snake-core --example gait`.

use snake_core::{Gait, LateralUndulation, Preset, Snake, StartPose};

fn main() -> snake_core::Result<()> {
    let config = Preset::Paper.config(10);
    let mut snake = Snake::new(&config, StartPose::resting(config.half_extent))?;
    let mut gait = LateralUndulation::default();
    let mut targets = vec![0.0; snake.joints()];

    let start = snake.base_state()?.pose.position;
    for step in 1..=5 * 240 {
        gait.next_targets(&mut targets);
        snake.set_targets(&targets)?;
        snake.step()?;
        if step % 240 == 0 {
            let pose = snake.base_state()?.pose;
            let moved: nalgebra::Vector3<f64> = pose.position - start;
            println!(
                "t = {:>3.1} s  head at ({:+.3}, {:+.3})  moved {:.3} m  yaw {:+.3} rad",
                snake.time(),
                pose.position.x,
                pose.position.y,
                moved.xy().norm(),
                pose.yaw()
            );
        }
    }
    Ok(())
}
