//! The integration tests, one binary with a module per topic: each runs the real `somnurbs`
//! binary in temporary folders (`common::Case`), on the generated data sets and, where a test
//! needs them, the third-party scans in `data/` at the top of the clone (or `SOMNURBS_DATA`).

mod common;

mod bounds;
mod cli;
mod compare_guards;
mod drift;
mod exact_certificate;
mod folders;
mod friction;
mod fuzz;
mod hostile;
mod html_report;
mod own_data;
mod plans;
mod real_scan;
mod records;
mod resume;
mod robust;
mod seed001;
mod seed002;
mod seed003;
mod seed004;
mod simd;
mod slurm;
mod sweep;
