//! Performance atlas: over a grid of poses, the actuator positions and the actuator
//! velocity and acceleration a given pose rate and acceleration capacity needs
//! (seed 004 fig. 6: slider rates for `z'' = 1 g`, `theta'' = 30 rad/s^2`).

use nalgebra::SVector;
use rayon::prelude::*;

use super::{check_axes, grid_point, reach, GridAxis};
use crate::error::{Error, Result};
use crate::limits::LimitName;
use crate::mechanism::Mechanism;

/// Largest pose-coordinate rates and accelerations (internal units: mm, rad per s,
/// per s^2), one magnitude per pose coordinate; 0 for a coordinate that does not move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capacity<const P: usize> {
    /// `|x'_k| <= velocity[k]`.
    pub velocity: SVector<f64, P>,
    /// `|x''_k| <= acceleration[k]`.
    pub acceleration: SVector<f64, P>,
}

/// One atlas point.
#[derive(Debug, Clone, PartialEq)]
pub struct AtlasPoint<const A: usize> {
    /// Within every limit.
    pub reachable: bool,
    /// The first violated limit, when not reachable.
    pub binding: Option<LimitName>,
    /// Actuator positions (NaN where the inverse solution does not exist).
    pub q: SVector<f64, A>,
    /// Per actuator, the largest `|q'|` over all pose rates within the capacity.
    pub velocity: SVector<f64, A>,
    /// Per actuator, the largest `|q''|` over all pose accelerations within the
    /// capacity, at the worst pose rate of largest magnitude in every coordinate.
    pub acceleration: SVector<f64, A>,
}

/// An atlas over a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Atlas<const A: usize> {
    /// The grid axes (first varies slowest).
    pub axes: Vec<GridAxis>,
    /// The pose every point starts from.
    pub base: Vec<f64>,
    /// One point per grid node, row-major.
    pub points: Vec<AtlasPoint<A>>,
}

/// Worst-case actuator rates at pose `x`: with `q' = J x'` and
/// `q'' = J x'' + (J' x')`, per actuator `i`
///
/// ```text
/// max |q'_i|  = sum_k |J_ik| v_k
/// max |q''_i| = max over x' in {+-v} of ( sum_k |J_ik| a_k + |(J' x')_i| )
/// ```
///
/// where the velocity term is quadratic in `x'`, so half of the `2^n` sign vectors
/// of the `n` moving coordinates suffice (`n <= 12`). Each actuator gets its own worst
/// direction: the map says what each drive must be able to do.
pub fn worst_rates<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    cap: &Capacity<P>,
) -> Result<(SVector<f64, A>, SVector<f64, A>)>
where
    M: Mechanism<P, A> + ?Sized,
{
    let j = m.jacobian(x)?.abs();
    let vel = j * cap.velocity;
    let base_acc = j * cap.acceleration;
    let moving: Vec<usize> = (0..P).filter(|&k| cap.velocity[k] > 0.0).collect();
    if moving.len() > 12 {
        return Err(Error::InvalidInput {
            what: "atlas capacity".into(),
            message: "at most 12 moving coordinates".into(),
        });
    }
    let mut acc = base_acc;
    if !moving.is_empty() {
        let zero = SVector::<f64, P>::zeros();
        for signs in 0..(1u32 << (moving.len() - 1)) {
            let mut xd = zero;
            for (b, &k) in moving.iter().enumerate() {
                let s = if signs >> b & 1 == 1 { -1.0 } else { 1.0 };
                xd[k] = s * cap.velocity[k];
            }
            let c = m.actuator_motion(x, &xd, &zero)?.qdd;
            for i in 0..A {
                acc[i] = acc[i].max(base_acc[i] + c[i].abs());
            }
        }
    }
    Ok((vel, acc))
}

/// The atlas of a grid of poses (`base` with the axis coordinates set), in parallel.
/// `progress` is called with the number of points done.
pub fn atlas<M, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    axes: &[GridAxis],
    cap: &Capacity<P>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Atlas<A>>
where
    M: Mechanism<P, A>,
{
    check_axes(axes, P)?;
    if !(cap.velocity.iter().chain(cap.acceleration.iter())).all(|v| v.is_finite() && *v >= 0.0) {
        return Err(Error::InvalidInput {
            what: "atlas capacity".into(),
            message: "rates and accelerations must be finite and >= 0".into(),
        });
    }
    let counts: Vec<usize> = axes.iter().map(|a| a.count()).collect();
    let total: usize = counts.iter().product();
    let chunk = 1024;
    let nan = SVector::<f64, A>::repeat(f64::NAN);
    let points = (0..total)
        .into_par_iter()
        .with_min_len(chunk)
        .map_init(Vec::new, |v, k| {
            let x = grid_point(base, axes, &counts, k);
            // Limits only: the atlas needs no condition number (an eigenproblem per
            // point for some machines).
            let (q, binding) = reach(m, &x, v);
            let (velocity, acceleration) = match q {
                Some(_) => worst_rates(m, &x, cap).unwrap_or((nan, nan)),
                None => (nan, nan),
            };
            if k % chunk == chunk - 1 {
                progress(chunk as u64);
            }
            AtlasPoint {
                reachable: binding.is_none(),
                binding,
                q: q.unwrap_or(nan),
                velocity,
                acceleration,
            }
        })
        .collect();
    Ok(Atlas {
        axes: axes.to_vec(),
        base: base.as_slice().to_vec(),
        points,
    })
}
