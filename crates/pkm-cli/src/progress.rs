//! Progress bars on long work (indicatif draws them on stderr, and not at all when
//! stderr is not a terminal).

use indicatif::{ProgressBar, ProgressStyle};

/// A bar over `total` units when `total` exceeds `threshold`, with `template` (an
/// indicatif template such as `{bar:40} {pos}/{len} points {eta}`).
pub fn bar(total: u64, threshold: u64, template: &str) -> Option<ProgressBar> {
    (total > threshold).then(|| {
        let b = ProgressBar::new(total);
        b.set_style(
            ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b
    })
}
