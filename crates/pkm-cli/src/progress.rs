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

/// A spinner counting units of work whose total is not known in advance, when `show`,
/// with `template` (`{spinner} {pos} points {elapsed}`); ticks ten times a second.
pub fn spinner(show: bool, template: &str) -> Option<ProgressBar> {
    show.then(|| {
        let b = ProgressBar::new_spinner();
        b.set_style(
            ProgressStyle::with_template(template)
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        b.enable_steady_tick(std::time::Duration::from_millis(100));
        b
    })
}
