//! `step_cost` (examples/step_cost.rs), compiled in a crate that depends on the kernel as a
//! host does: cargo builds the kernel with this crate's release profile, not the kernel's own.
//! See README.md.

#[path = "../../../examples/step_cost.rs"]
mod step_cost;

fn main() {
    step_cost::main();
}
