//! What a report says of a run's operator ([`OperatorSummary`]: the keys of `solve --json`
//! that concern it) and of what crossed to a GPU and back ([`DeviceTransfers`]).

use serde::Serialize;

use crate::gpu;
use crate::operator::OperatorStats;
use crate::visibility::PairStats;

/// What a report says of the operator (the keys of `solve --json` that concern it).
#[derive(Clone, Debug, Serialize)]
pub struct OperatorSummary {
    /// `dense` or `compressed`.
    pub operator: &'static str,
    /// The GPU adapter, when the GPU evaluated the entries.
    pub device: Option<String>,
    /// Time to plan and assemble (or build) the operator.
    pub setup_seconds: f64,
    /// One-time preparation of the backend.
    pub preparation_seconds: f64,
    /// Pair classes.
    pub pairs: PairStats,
    /// Relative tolerance of the low-rank blocks (compressed operator).
    pub compression_tolerance: Option<f64>,
    /// Memory of the stored operator, in bytes.
    pub operator_bytes: u64,
    /// What the compressed operator's build was estimated to hold at its peak before it began
    /// (none for the dense matrix, whose 8 n² bytes are known, or an operator read from a file).
    pub memory_estimate_bytes: Option<u64>,
    /// Block statistics of the compressed operator.
    #[serde(flatten)]
    pub blocks: Option<OperatorStats>,
    /// Where the dense matrix assembled on the GPU lives, and what crossed.
    #[serde(flatten)]
    pub transfers: Option<DeviceTransfers>,
}

/// Where a matrix assembled on the GPU is kept and what crossed between host and device
/// (`operator_location`, `bytes_uploaded`, `bytes_read_back`, `gpu_submissions`,
/// `device_idle_fraction` in reports).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DeviceTransfers {
    /// `device` (kept there, products there) or `host` (read back).
    pub operator_location: &'static str,
    /// Bytes written to the device.
    pub bytes_uploaded: u64,
    /// Bytes read back.
    pub bytes_read_back: u64,
    /// Command submissions.
    pub gpu_submissions: u64,
    /// At most this share of the setup and solve's wall time was the device idle: one less the
    /// host's waits for it over that time (the device was busy at least while the host
    /// waited; it may have been busy longer).
    pub device_idle_fraction: f64,
    /// Host time spent waiting for the device.
    #[serde(skip)]
    pub device_wait_seconds: f64,
    /// For an operator kept on the device, the precision of its entries there and what that
    /// did to it (`storage`, `storage_error`, `storage_solution_bound`).
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub storage: Option<gpu::StorageError>,
}

impl DeviceTransfers {
    /// After `traffic`, of an operator kept on the device in `storage`, or read back (`None`).
    pub(super) fn new(traffic: gpu::DeviceTraffic, storage: Option<gpu::StorageError>) -> Self {
        Self {
            operator_location: if storage.is_some() { "device" } else { "host" },
            bytes_uploaded: traffic.bytes_uploaded,
            bytes_read_back: traffic.bytes_read_back,
            gpu_submissions: traffic.gpu_submissions,
            device_idle_fraction: 0.0,
            device_wait_seconds: traffic.device_wait_seconds,
            storage,
        }
    }

    /// With the idle share of `wall_seconds` (setup and solve) filled in.
    pub fn over(mut self, wall_seconds: f64) -> Self {
        self.device_idle_fraction = if wall_seconds > 0.0 {
            (1.0 - self.device_wait_seconds / wall_seconds).clamp(0.0, 1.0)
        } else {
            0.0
        };
        self
    }
}
