//! The double net: two `nx x ny` views (bottom, top) glued along their border.
//!
//! The thesis uses the same indexing twice: for the DNSOM neurons (Section 4.2.3, Tables 4.2-4.3,
//! Fig. 4.3) and for the pair of control nets of the improved approach (Fig. 5.2, Table 5.1).
//! Index vector (i, j, k): i in 0..nx, j in 0..ny; k = 1 on the border (i = 0, nx-1, j = 0, ny-1),
//! which both views share; k = 0 bottom interior, k = 2 top interior. Class numbers are allocated
//! bottom view first, then top, i-major and j-minor; a shared border position carries one class
//! number (its first allocation, in the bottom view). Internally classes are 0-based; the thesis'
//! 1-based "class number" is `class + 1`.

/// The two organised surfaces of a DNSOM map (or any two-view grid): row-major `nx x ny` views,
/// position (i, j) at `i * ny + j`, sharing their border.
#[derive(Debug, Clone, PartialEq)]
pub struct TwoViewGrid {
    pub nx: usize,
    pub ny: usize,
    pub bottom: Vec<crate::geom::Point3>,
    pub top: Vec<crate::geom::Point3>,
}

impl TwoViewGrid {
    /// A trained DNSOM's weights, one per class, as a two-view grid (border positions share
    /// their class's weight); None when the grid has a side under 2 or there are fewer weights
    /// than classes.
    pub fn from_weights(
        nx: usize,
        ny: usize,
        weights: &[crate::geom::Point3],
    ) -> Option<TwoViewGrid> {
        let net = DoubleNet::new(nx, ny)?;
        if weights.len() < net.nov() {
            return None;
        }
        let view = |v: View| {
            (0..nx)
                .flat_map(|i| (0..ny).map(move |j| (i, j)))
                .map(|(i, j)| weights[net.class(v, i, j)])
                .collect()
        };
        Some(TwoViewGrid { nx, ny, bottom: view(View::Bottom), top: view(View::Top) })
    }
}

/// Which of the two views a grid position belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum View {
    Bottom,
    Top,
}

impl View {
    pub const BOTH: [View; 2] = [View::Bottom, View::Top];

    pub fn name(self) -> &'static str {
        match self {
            View::Bottom => "bottom",
            View::Top => "top",
        }
    }
}

/// Class-number layout of a double net of `nx x ny` views.
#[derive(Debug, Clone, PartialEq)]
pub struct DoubleNet {
    pub nx: usize,
    pub ny: usize,
    class_bottom: Vec<usize>,
    class_top: Vec<usize>,
    /// First allocation (view, i, j) of every class, indexed by 0-based class.
    first: Vec<(View, usize, usize)>,
}

impl DoubleNet {
    /// Lay out a double net; `nx, ny >= 2` (smaller nets have no interior to tell the views apart).
    pub fn new(nx: usize, ny: usize) -> Option<DoubleNet> {
        if nx < 2 || ny < 2 {
            return None;
        }
        let n = nx * ny;
        let mut class_bottom = vec![0; n];
        let mut class_top = vec![0; n];
        let mut first = Vec::with_capacity(2 * n);
        for i in 0..nx {
            for j in 0..ny {
                class_bottom[i * ny + j] = first.len();
                first.push((View::Bottom, i, j));
            }
        }
        for i in 0..nx {
            for j in 0..ny {
                let at = i * ny + j;
                if is_border(nx, ny, i, j) {
                    class_top[at] = class_bottom[at];
                } else {
                    class_top[at] = first.len();
                    first.push((View::Top, i, j));
                }
            }
        }
        Some(DoubleNet { nx, ny, class_bottom, class_top, first })
    }

    /// Total number of neurons (or control points) of both views, NON = 2 nx ny (Eq. 4.1).
    pub fn non(&self) -> usize {
        2 * self.nx * self.ny
    }

    /// Number of distinct class numbers, NOV = 2 (nx ny - nx - ny + 2) (Eq. 4.2).
    pub fn nov(&self) -> usize {
        self.first.len()
    }

    /// Number of redundant (shared) positions, NOR = NON - NOV (Eq. 4.3).
    pub fn nor(&self) -> usize {
        self.non() - self.nov()
    }

    /// Row-major position of (i, j) inside one view.
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> usize {
        i * self.ny + j
    }

    /// Whether (i, j) lies on the shared border (k = 1).
    #[inline]
    pub fn is_border(&self, i: usize, j: usize) -> bool {
        is_border(self.nx, self.ny, i, j)
    }

    /// Index vector (i, j, k) of a position (Fig. 4.2).
    pub fn index_vector(&self, view: View, i: usize, j: usize) -> [usize; 3] {
        let k = if self.is_border(i, j) {
            1
        } else if view == View::Bottom {
            0
        } else {
            2
        };
        [i, j, k]
    }

    /// 0-based class of position (i, j) in `view`.
    #[inline]
    pub fn class(&self, view: View, i: usize, j: usize) -> usize {
        match view {
            View::Bottom => self.class_bottom[self.at(i, j)],
            View::Top => self.class_top[self.at(i, j)],
        }
    }

    /// 0-based classes of a whole view, row-major.
    pub fn classes(&self, view: View) -> &[usize] {
        match view {
            View::Bottom => &self.class_bottom,
            View::Top => &self.class_top,
        }
    }

    /// First allocation (view, i, j) of a 0-based class.
    pub fn first_allocation(&self, class: usize) -> (View, usize, usize) {
        self.first[class]
    }

    /// The 1-based class numbers of the four corners, Table 5.1: 1, ny, ny (nx - 1) + 1, nx ny.
    pub fn corner_class_numbers(&self) -> [usize; 4] {
        let (nx, ny) = (self.nx, self.ny);
        [
            self.class(View::Bottom, 0, 0) + 1,
            self.class(View::Bottom, 0, ny - 1) + 1,
            self.class(View::Bottom, nx - 1, 0) + 1,
            self.class(View::Bottom, nx - 1, ny - 1) + 1,
        ]
    }
}

#[inline]
fn is_border(nx: usize, ny: usize, i: usize, j: usize) -> bool {
    i == 0 || j == 0 || i + 1 == nx || j + 1 == ny
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_4_14_and_4_13_counts() {
        let cases = [
            (2, 3, 12, 6, 6),
            (3, 4, 24, 14, 10),
            (4, 5, 40, 26, 14),
            (5, 6, 60, 42, 18),
            (6, 7, 84, 62, 22),
            (7, 8, 112, 86, 26),
            (10, 8, 160, 128, 32),
            (20, 12, 480, 420, 60),
            (18, 30, 1080, 988, 92),
            (10, 10, 200, 164, 36),
            (20, 20, 800, 724, 76),
            (30, 30, 1800, 1684, 116),
        ];
        for (nx, ny, non, nov, nor) in cases {
            let net = DoubleNet::new(nx, ny).unwrap();
            assert_eq!((net.non(), net.nov(), net.nor()), (non, nov, nor), "{nx}x{ny}");
            assert_eq!(net.nov(), 2 * (nx * ny - nx - ny + 2));
        }
    }

    #[test]
    fn figure_4_3_class_numbers_4x5() {
        let net = DoubleNet::new(4, 5).unwrap();
        // Figure 4.3 (b), top view, read as rows j = 4..0 and columns i = 0..3.
        let top =
            [[5, 10, 15, 20], [4, 23, 26, 19], [3, 22, 25, 18], [2, 21, 24, 17], [1, 6, 11, 16]];
        for (r, row) in top.iter().enumerate() {
            let j = 4 - r;
            for (i, &c) in row.iter().enumerate() {
                assert_eq!(net.class(View::Top, i, j) + 1, c, "top ({i},{j})");
                assert_eq!(net.class(View::Bottom, i, j) + 1, i * 5 + j + 1, "bottom ({i},{j})");
            }
        }
        // Table 4.3: class 21 is (1,1,2), class 7 is (1,1,0).
        let (v, i, j) = net.first_allocation(20);
        assert_eq!(net.index_vector(v, i, j), [1, 1, 2]);
        let (v, i, j) = net.first_allocation(6);
        assert_eq!(net.index_vector(v, i, j), [1, 1, 0]);
    }

    #[test]
    fn figure_5_4_and_table_5_1() {
        let net = DoubleNet::new(3, 4).unwrap();
        assert_eq!(net.class(View::Top, 1, 1) + 1, 13);
        assert_eq!(net.class(View::Top, 1, 2) + 1, 14);
        for (nx, ny) in [(3, 4), (4, 5), (5, 6), (6, 7), (7, 8)] {
            let net = DoubleNet::new(nx, ny).unwrap();
            assert_eq!(net.corner_class_numbers(), [1, ny, ny * (nx - 1) + 1, nx * ny]);
        }
    }

    #[test]
    fn too_small_is_refused() {
        assert!(DoubleNet::new(1, 5).is_none());
        assert!(DoubleNet::new(5, 1).is_none());
    }
}
