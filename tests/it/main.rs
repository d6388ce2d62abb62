//! The integration tests: one binary, one module per subject. Each subject is tested in one
//! place; `support` holds what they share (the binary, the LIGGGHTS check, sweep files, engines
//! and readers of a sweep directory).
//!
//! Sweeps that only exercise the directory run on the deterministic fake executor or the
//! stand-in engine; those whose path involves LIGGGHTS run it for real on small scenes and skip,
//! saying so, when it is not installed. `cargo test --release --test it SUBJECT::` runs one subject.

mod support;

// What a user types: sweep files, flags, values and units; the designs they ask for.
mod design;
mod input;

// Running a sweep: the pool, failed runs, interruption and resume, several processes on one
// directory, what the directory holds, the engine, the screen, clusters, the adaptive design.
mod adapt;
mod calibrate;
mod cluster;
mod concurrency;
mod engine;
mod extend;
mod failures;
mod pool;
mod resume;
mod screen;
mod standin;
mod store;

// What a run measures: one point, the recoater's bounds, the steady state, the timestep's stability edge, the
// fidelity presets, VTK output, the contact model and the dump parser.
mod contact;
mod decks;
mod dump;
mod fidelity;
mod laid;
mod layers;
mod point;
mod pour;
mod powders;
mod recoater;
mod roller;
mod stability;
mod steady;
mod study_layers;
mod vtk;
mod warm;

// What a sweep ends with: statistics, convergence and the report.
mod report;

// What a hostile run found, each defect with its regression test; the answer a sweep ends with.
mod answer;
mod hostile;

// How the code is laid out: the layering of src/ that docs/architecture.md states, and its steps
// for adding a layout.
mod adding_a_layout;
mod architecture;
