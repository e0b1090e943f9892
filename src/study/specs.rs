//! The studies as data: what each one runs and the values the paper prints.

use crate::assembly::Quadrature;
use crate::discretization::Method;
use crate::gpu::Precision;
use crate::kernels::graded::DEFAULT_NEAR;
use crate::mesh::S5Diagonals;
use crate::pipeline::MeshChoice;
use crate::problems::TrueSolution;
use crate::quadrature::ImtRule;
use crate::scene::BuiltinScene;
use crate::surface_error::DEFAULT_LATTICE;

/// Where a series is assembled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// Where the study was asked to run (`--backend`, CPU by default).
    Selected,
    /// Always on the CPU (the graded quadratures have no GPU kernel).
    Cpu,
    /// On the GPU in this precision, when one is available or asked for.
    Gpu(Precision),
}

/// One sequence of runs over increasing n: a column group of a paper table or a line of a figure.
#[derive(Clone, Debug)]
pub struct Series {
    /// Surface.
    pub scene: BuiltinScene,
    /// Mesh.
    pub mesh: MeshChoice,
    /// Collocation method.
    pub method: Method,
    /// True solution.
    pub solution: TrueSolution,
    /// How the collocation integrals are evaluated.
    pub quadrature: Quadrature,
    /// IMT subintervals of the exact method (linear collocation).
    pub imt_nodes: usize,
    /// Where the matrix is assembled.
    pub placement: Placement,
    /// The paper's printed (n, E_n).
    pub paper: &'static [(usize, f64)],
    /// The paper's printed (n, setup seconds) (Tables 4.1, 4.2; an HP C200 of 1999).
    pub paper_seconds: &'static [(usize, f64)],
}

impl Series {
    fn new(scene: BuiltinScene, mesh: MeshChoice, method: Method, solution: TrueSolution) -> Self {
        Self {
            scene,
            mesh,
            method,
            solution,
            quadrature: Quadrature::Exact,
            imt_nodes: ImtRule::PAPER_NODES,
            placement: Placement::Selected,
            paper: &[],
            paper_seconds: &[],
        }
    }

    fn paper(mut self, paper: &'static [(usize, f64)]) -> Self {
        self.paper = paper;
        self
    }

    fn timed(mut self, quadrature: Quadrature, placement: Placement) -> Self {
        self.quadrature = quadrature;
        self.placement = placement;
        self
    }

    fn imt_nodes(mut self, nodes: usize) -> Self {
        self.imt_nodes = nodes;
        self
    }

    fn paper_seconds(mut self, seconds: &'static [(usize, f64)]) -> Self {
        self.paper_seconds = seconds;
        self
    }

    /// A label that tells the series apart within a study.
    pub fn label(&self) -> String {
        let device = match self.placement {
            Placement::Selected => String::new(),
            Placement::Cpu => " cpu".into(),
            Placement::Gpu(p) => format!(" gpu-{}", p.name()),
        };
        let imt = if self.imt_nodes != ImtRule::PAPER_NODES && self.method != Method::Centroid {
            format!("(imt {})", self.imt_nodes)
        } else {
            String::new()
        };
        format!(
            "{} {} {} {}{imt}{device}",
            self.scene,
            self.mesh.name(),
            self.method.name(),
            self.quadrature.label()
        )
    }
}

/// What a study produces besides its rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A table of errors and ratios E_{n/4}/E_n.
    Table,
    /// Errors against n, log-log, with fitted rates (PNG and SVG).
    Convergence,
    /// Setup times and errors of several ways to compute the same solutions; each row also gets
    /// its integration error against the exact method on the CPU at the same n.
    Timing {
        /// Also plot error against setup time with the Pareto front.
        plot: bool,
    },
}

/// A study: series of runs for increasing n.
#[derive(Clone, Debug)]
pub struct StudySpec {
    /// Id on the command line.
    pub id: &'static str,
    /// Title.
    pub title: &'static str,
    /// The runs.
    pub series: Vec<Series>,
    /// Largest n run by default (the paper's largest, where it has a table).
    pub default_max_n: usize,
    /// What the study produces.
    pub kind: Kind,
    /// Also measure the errors over all of S at the points of this lattice.
    pub surface_lattice: Option<usize>,
    /// Remarks printed with the results.
    pub notes: &'static [&'static str],
}

const LINEAR: Method = Method::Linear { alpha: Method::PAPER_ALPHA };
const FOUR: BuiltinScene = BuiltinScene::FourPiece;
const FIVE: BuiltinScene = BuiltinScene::FivePiece;
const UNIFORM: MeshChoice = MeshChoice::Uniform;
const DISCONTINUITY: MeshChoice = MeshChoice::Discontinuity(S5Diagonals::Paper);

/// Uniform and discontinuity meshes of one surface.
fn both_meshes(scene: BuiltinScene, method: Method, solution: TrueSolution) -> Vec<Series> {
    [UNIFORM, DISCONTINUITY].map(|mesh| Series::new(scene, mesh, method, solution)).into()
}

fn table_3_1() -> StudySpec {
    StudySpec {
        id: "table-3.1",
        title: "Table 3.1: centroid method errors for u = x^2 + y^2 (3.2), uniform mesh",
        series: vec![
            Series::new(FOUR, UNIFORM, Method::Centroid, TrueSolution::X2Y2).paper(&[
                (8, 6.67),
                (32, 0.910),
                (128, 0.214),
                (512, 0.0487),
                (2048, 0.0123),
            ]),
            Series::new(FIVE, UNIFORM, Method::Centroid, TrueSolution::X2Y2).paper(&[
                (10, 6.58),
                (40, 3.28),
                (160, 1.86),
                (640, 0.991),
                (2560, 0.511),
            ]),
        ],
        default_max_n: 2560,
        kind: Kind::Table,
        surface_lattice: None,
        notes: &[],
    }
}

fn table_3_2() -> StudySpec {
    StudySpec {
        id: "table-3.2",
        title: "Table 3.2: centroid method errors for u of (3.3) with (beta, gamma) = (0.5, 1.5), 4-piece surface",
        series: both_meshes(FOUR, Method::Centroid, TrueSolution::Shadow { beta: 0.5, gamma: 1.5 }),
        default_max_n: 2048,
        kind: Kind::Table,
        surface_lattice: None,
        notes: &[
            "The paper gives ratios for the discontinuity mesh only: the uniform mesh's are irregular.",
        ],
    }
}

fn table_3_3() -> StudySpec {
    StudySpec {
        id: "table-3.3",
        title: "Table 3.3: centroid method errors for u of (3.4) with beta = 0.5, 5-piece surface",
        series: {
            let mut s = both_meshes(FIVE, Method::Centroid, TrueSolution::Edge { beta: 0.5 });
            s[0].paper = &[(10, 0.286), (40, 0.174), (160, 0.124), (640, 0.0879), (2560, 0.0622)];
            s[1].paper = &[(30, 0.0749), (120, 0.0255), (480, 0.0177), (1920, 0.0125)];
            s
        },
        default_max_n: 2560,
        kind: Kind::Table,
        surface_lattice: None,
        notes: &[],
    }
}

fn table_3_4() -> StudySpec {
    StudySpec {
        id: "table-3.4",
        title: "Table 3.4: piecewise linear collocation (alpha = 1/6) errors for u = x^2 + y^2 (3.2), uniform mesh",
        series: vec![
            Series::new(FOUR, UNIFORM, LINEAR, TrueSolution::X2Y2).paper(&[
                (8, 1.43),
                (32, 0.213),
                (128, 8.89e-3),
                (512, 2.74e-4),
            ]),
            Series::new(FIVE, UNIFORM, LINEAR, TrueSolution::X2Y2).paper(&[
                (10, 1.44),
                (40, 0.317),
                (160, 0.0796),
                (640, 0.0199),
            ]),
        ],
        default_max_n: 640,
        kind: Kind::Table,
        surface_lattice: None,
        notes: &[],
    }
}

fn table_3_5() -> StudySpec {
    let edge = TrueSolution::Edge { beta: 0.5 };
    StudySpec {
        id: "table-3.5",
        title: "Table 3.5: piecewise linear collocation (alpha = 1/6) errors for u of (3.4) with beta = 0.5, uniform mesh",
        series: vec![
            Series::new(FOUR, UNIFORM, LINEAR, edge),
            Series::new(FIVE, UNIFORM, LINEAR, edge),
        ],
        default_max_n: 640,
        kind: Kind::Table,
        surface_lattice: None,
        notes: &[
            "The caption names (3.4) with beta = 1/2, the text (3.3) with beta = 1/2. We follow the caption: \
             the text expects O(h^0.5) on the 5-piece surface from (2.32), the singularity (2.31) at an edge \
             shared by two faces, which (3.4) has at y = A and (3.3) does not (it vanishes for y > 2B); \
             the 5-piece ratios below are 2^0.5 = 1.41 as expected, while (3.3) gives irregular ones.",
        ],
    }
}

fn table_4_1() -> StudySpec {
    let x2y2 = TrueSolution::X2Y2;
    let series = |q: Quadrature, placement| {
        Series::new(FIVE, UNIFORM, Method::Centroid, x2y2).timed(q, placement)
    };
    StudySpec {
        id: "table-4.1",
        title: "Table 4.1: centroid collocation errors and setup times for u = x^2 + y^2 (3.2), 5-piece surface, by integration method",
        series: vec![
            series(Quadrature::Exact, Placement::Cpu)
                .paper(&[(40, 3.28), (160, 1.86), (640, 0.991), (2560, 0.511)])
                .paper_seconds(&[(40, 0.031), (160, 0.469), (640, 7.12), (2560, 111.0)]),
            series(Quadrature::PAPER_SEVEN_POINT, Placement::Cpu)
                .paper(&[(40, 3.28), (160, 1.86), (640, 0.991), (2560, 0.510)])
                .paper_seconds(&[(40, 4.11), (160, 32.7), (640, 163.0), (2560, 846.0)]),
            series(Quadrature::paper_gauss(1, 3), Placement::Cpu)
                .paper(&[(40, 3.28), (160, 1.85), (640, 0.986), (2560, 0.506)])
                .paper_seconds(&[(40, 0.594), (160, 4.93), (640, 84.2), (2560, 2940.0)]),
            series(Quadrature::Exact, Placement::Gpu(Precision::F64)),
        ],
        default_max_n: 2560,
        kind: Kind::Timing { plot: false },
        surface_lattice: None,
        notes: TIMING_NOTES,
    }
}

fn table_4_2() -> StudySpec {
    let x2y2 = TrueSolution::X2Y2;
    let series =
        |q: Quadrature, placement| Series::new(FIVE, UNIFORM, LINEAR, x2y2).timed(q, placement);
    StudySpec {
        id: "table-4.2",
        title: "Table 4.2: piecewise linear collocation errors and setup times for u = x^2 + y^2 (3.2), 5-piece surface, by integration method",
        series: vec![
            series(Quadrature::Exact, Placement::Cpu)
                .paper(&[(10, 1.44), (40, 0.317), (160, 0.0796), (640, 0.0199)])
                .paper_seconds(&[(10, 0.164), (40, 1.79), (160, 29.3), (640, 474.0)]),
            series(Quadrature::paper_gauss(1, 4), Placement::Cpu)
                .paper(&[(10, 1.44), (40, 0.317), (160, 0.0795), (640, 0.103)])
                .paper_seconds(&[(10, 3.52), (40, 34.8), (160, 158.0), (640, 558.0)]),
            series(Quadrature::paper_gauss(1, 5), Placement::Cpu)
                .paper(&[(10, 1.44), (40, 0.317), (160, 0.0796), (640, 0.0199)])
                .paper_seconds(&[(10, 14.2), (40, 139.0), (160, 625.0), (640, 2150.0)]),
            series(Quadrature::Exact, Placement::Gpu(Precision::F64)),
        ],
        default_max_n: 640,
        kind: Kind::Timing { plot: false },
        surface_lattice: None,
        notes: TIMING_NOTES,
    }
}

const TIMING_NOTES: &[&str] = &[
    "setup s: planning and assembly of the matrix, best of up to 3 runs; the paper's times are from a \
     200 MHz HP C200 (1999).",
    "int. err: max |u_n - u_n(exact, cpu)| / max |u_n(exact, cpu)| at the nodes, the change the \
     integration method (or the GPU) makes in the solution.",
    "The GPU column runs where an adapter is found (or when the GPU is asked for); asking for the CPU leaves it out.",
];

fn error_vs_time() -> StudySpec {
    let x2y2 = TrueSolution::X2Y2;
    let mut series = Vec::new();
    for (method, levels, imt_nodes) in
        [(Method::Centroid, 1..=5, &[][..]), (LINEAR, 3..=6, &[32, 64][..])]
    {
        let base = || Series::new(FIVE, UNIFORM, method, x2y2);
        series.push(base().timed(Quadrature::Exact, Placement::Cpu));
        for &nodes in imt_nodes {
            series.push(base().timed(Quadrature::Exact, Placement::Cpu).imt_nodes(nodes));
        }
        series.push(base().timed(Quadrature::Exact, Placement::Gpu(Precision::F64)));
        series.push(base().timed(Quadrature::Exact, Placement::Gpu(Precision::F32)));
        for max_level in levels.clone() {
            let q = Quadrature::SevenPoint { max_level, near_ratio: DEFAULT_NEAR };
            series.push(base().timed(q, Placement::Cpu));
        }
        for max_level in levels {
            series.push(base().timed(Quadrature::paper_gauss(1, max_level), Placement::Cpu));
        }
    }
    StudySpec {
        id: "error-vs-time",
        title: "Error against setup time: centroid and linear collocation, u = x^2 + y^2 (3.2), 5-piece surface, uniform mesh",
        series,
        default_max_n: 2560,
        kind: Kind::Timing { plot: true },
        surface_lattice: None,
        notes: TIMING_NOTES,
    }
}

fn grading() -> StudySpec {
    let x2y2 = TrueSolution::X2Y2;
    let mut series = vec![
        Series::new(FIVE, UNIFORM, Method::Centroid, x2y2).timed(Quadrature::Exact, Placement::Cpu),
        Series::new(FIVE, UNIFORM, LINEAR, x2y2).timed(Quadrature::Exact, Placement::Cpu),
    ];
    for near_ratio in [0.25, 0.5, 1.0, 2.0, 4.0] {
        let centroid =
            |q| Series::new(FIVE, UNIFORM, Method::Centroid, x2y2).timed(q, Placement::Cpu);
        series.push(centroid(Quadrature::SevenPoint { max_level: 3, near_ratio }));
        series.push(centroid(Quadrature::Gauss { ibase: 1, max_level: 3, near_ratio }));
        let linear = |q| Series::new(FIVE, UNIFORM, LINEAR, x2y2).timed(q, Placement::Cpu);
        series.push(linear(Quadrature::Gauss { ibase: 1, max_level: 4, near_ratio }));
        series.push(linear(Quadrature::Gauss { ibase: 1, max_level: 5, near_ratio }));
    }
    StudySpec {
        id: "grading",
        title: "Sensitivity of the 7-point and Gauss methods to the grading distance (full level within near-ratio element diameters), Tables 4.1 and 4.2 settings",
        series,
        default_max_n: 640,
        kind: Kind::Timing { plot: false },
        surface_lattice: None,
        notes: TIMING_NOTES,
    }
}

fn figure(
    id: &'static str,
    title: &'static str,
    series: Vec<Series>,
    default_max_n: usize,
    surface_lattice: Option<usize>,
) -> StudySpec {
    StudySpec {
        id,
        title,
        series,
        default_max_n,
        kind: Kind::Convergence,
        surface_lattice,
        notes: &[],
    }
}

impl StudySpec {
    /// All studies.
    pub fn all() -> Vec<Self> {
        let shadow = |beta| TrueSolution::Shadow { beta, gamma: 1.5 };
        let figure_3_7 = [FOUR, FIVE]
            .into_iter()
            .flat_map(|scene| both_meshes(scene, LINEAR, shadow(1.0)))
            .collect();
        vec![
            table_3_1(),
            table_3_2(),
            table_3_3(),
            table_3_4(),
            table_3_5(),
            table_4_1(),
            table_4_2(),
            figure(
                "figure-3.4",
                "Figure 3.4: centroid method errors with uniform and discontinuity meshes, u = x^2 + y^2 (3.2), 5-piece surface",
                both_meshes(FIVE, Method::Centroid, TrueSolution::X2Y2),
                2560,
                None,
            ),
            figure(
                "figure-3.5",
                "Figure 3.5: centroid method errors at the nodes for u of (3.3) with (beta, gamma) = (1.0, 1.5), 4-piece surface",
                both_meshes(FOUR, Method::Centroid, shadow(1.0)),
                2048,
                None,
            ),
            figure(
                "figure-3.6",
                "Figure 3.6: centroid method errors at the nodes for u of (3.3) with (beta, gamma) = (0.5, 1.5), 4-piece surface",
                both_meshes(FOUR, Method::Centroid, shadow(0.5)),
                2048,
                None,
            ),
            figure(
                "figure-3.7",
                "Figure 3.7: piecewise linear collocation errors for u of (3.3) with (beta, gamma) = (1.0, 1.5), at the nodes and over all of S",
                figure_3_7,
                1536,
                Some(DEFAULT_LATTICE),
            ),
            error_vs_time(),
            grading(),
        ]
    }

    /// The study with this id.
    pub fn find(id: &str) -> Option<Self> {
        Self::all().into_iter().find(|s| s.id == id)
    }
}

/// Ids of all studies.
pub fn study_ids() -> Vec<&'static str> {
    let mut ids: Vec<&'static str> = StudySpec::all().iter().map(|s| s.id).collect();
    ids.extend(crate::study::stability::STUDY_IDS);
    ids.push("compression");
    ids.push("estimates");
    ids.push("cities");
    ids
}
