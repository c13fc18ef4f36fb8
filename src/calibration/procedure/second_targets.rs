//! The points a coupling fit (eqs. 14-15) was fitted to, kept in memory for the outlier test
//! that refits them ([`SecondTargetData`]).

/// What a coupling fit (eqs. 14-15) was fitted to, point by point: where the result came from,
/// not what it is. Two reports with the same coupling are equal whatever their data, and a
/// report read back from a file has none.
#[derive(Clone, Debug, Default)]
pub struct SecondTargetData {
    /// Each second-target point's step in the file.
    pub steps: Vec<usize>,
    /// The driving joint's active angle at each \[rad\].
    pub active_rad: Vec<f64>,
    /// The driven joint's passive displacement since the first point \[rad\].
    pub passive_rad: Vec<f64>,
    /// Each point's distance from the driven axis \[m\]: what turns an angle into a distance.
    pub lever_arms_m: Vec<f64>,
}

impl PartialEq for SecondTargetData {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}
