//! The paper's tables as data: what each one runs and the values it prints.

use crate::discretization::Method;
use crate::pipeline::MeshChoice;
use crate::problems::TrueSolution;
use crate::scene::BuiltinScene;

/// One column group of a paper table (one surface and mesh).
#[derive(Clone, Debug)]
pub struct TableColumn {
    /// Surface.
    pub scene: BuiltinScene,
    /// Mesh.
    pub mesh: MeshChoice,
    /// The paper's printed (n, E_n).
    pub paper: &'static [(usize, f64)],
}

/// A study: a method and true solution run over surfaces and meshes for increasing n.
#[derive(Clone, Debug)]
pub struct StudySpec {
    /// Id on the command line.
    pub id: &'static str,
    /// Title.
    pub title: &'static str,
    /// Collocation method.
    pub method: Method,
    /// True solution.
    pub solution: TrueSolution,
    /// Surfaces and meshes.
    pub columns: Vec<TableColumn>,
    /// Largest n of the paper's table.
    pub paper_max_n: usize,
}

const LINEAR: Method = Method::Linear { alpha: Method::PAPER_ALPHA };

impl StudySpec {
    /// All studies.
    pub fn all() -> Vec<Self> {
        vec![
            Self {
                id: "table-3.1",
                title: "Table 3.1: centroid method errors for u = x^2 + y^2 (3.2), uniform mesh",
                method: Method::Centroid,
                solution: TrueSolution::X2Y2,
                columns: vec![
                    TableColumn {
                        scene: BuiltinScene::FourPiece,
                        mesh: MeshChoice::Uniform,
                        paper: &[
                            (8, 6.67),
                            (32, 0.910),
                            (128, 0.214),
                            (512, 0.0487),
                            (2048, 0.0123),
                        ],
                    },
                    TableColumn {
                        scene: BuiltinScene::FivePiece,
                        mesh: MeshChoice::Uniform,
                        paper: &[(10, 6.58), (40, 3.28), (160, 1.86), (640, 0.991), (2560, 0.511)],
                    },
                ],
                paper_max_n: 2560,
            },
            Self {
                id: "table-3.4",
                title: "Table 3.4: piecewise linear collocation (alpha = 1/6) errors for u = x^2 + y^2 (3.2), uniform mesh",
                method: LINEAR,
                solution: TrueSolution::X2Y2,
                columns: vec![
                    TableColumn {
                        scene: BuiltinScene::FourPiece,
                        mesh: MeshChoice::Uniform,
                        paper: &[(8, 1.43), (32, 0.213), (128, 8.89e-3), (512, 2.74e-4)],
                    },
                    TableColumn {
                        scene: BuiltinScene::FivePiece,
                        mesh: MeshChoice::Uniform,
                        paper: &[(10, 1.44), (40, 0.317), (160, 0.0796), (640, 0.0199)],
                    },
                ],
                paper_max_n: 640,
            },
        ]
    }

    /// The study with this id.
    pub fn find(id: &str) -> Option<Self> {
        Self::all().into_iter().find(|s| s.id == id)
    }

    /// Largest n of the paper's table.
    pub fn largest_n(&self) -> usize {
        self.paper_max_n
    }
}

/// Ids of all studies.
pub fn study_ids() -> Vec<&'static str> {
    StudySpec::all().iter().map(|s| s.id).collect()
}
