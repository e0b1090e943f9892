//! Reports: plain-text tables for people, JSON for programs, plots and NumPy files.

mod city_study;
mod compression_study;
mod estimate_study;
mod json;
mod nodes_csv;
mod npy;
pub mod plot;
mod render;
mod sparse;
mod stability_tables;
mod study_figures;
mod study_table;
mod table;
mod urban;
mod vtk;

pub use city_study::city_table;
pub use compression_study::{compression_table, write_compression_figure};
pub use estimate_study::estimate_table;
pub use json::write_json;
pub use nodes_csv::write_node_csv;
pub use npy::{write_npy, write_npy_vector};
pub use render::{Camera, DEFAULT_VIEW, Tone, render_png};
pub use sparse::{CsrRows, write_mtx, write_npz};
pub use stability_tables::{stability_table, stiff_table};
pub use study_figures::write_study_figures;
pub use study_table::study_table;
pub use table::TableFormat;
pub use urban::{
    NETSW_HEADER, TIMEDEPSW_HEADER, UrbanExport, VFSPARSE_THRESHOLD, facet_elements,
    timedepsw_seconds,
};
pub use vtk::{write_cell_vtu, write_vtu};
