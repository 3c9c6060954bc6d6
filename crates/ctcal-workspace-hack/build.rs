// A build script makes cargo resolve the `[build-dependencies]` (the proc macros' `syn`
// features among them) under the same feature set for every build.
fn main() {}
