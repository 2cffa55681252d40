//! Elastic energy of a fibre, split by deformation mode.

/// Elastic energy by mode, in the scene's energy unit (mass length² / time²).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energies {
    /// Axial stretching (L2020 eq. 11; S2023 first term of eq. 9).
    pub stretch: f64,
    /// Bending (L2020 eqs. 14-17, 21-24; S2023 second term of eq. 9, linear form).
    pub bend: f64,
    /// Torsion (L2020 eqs. 19-20). Zero in 2D and for the bead-spring model.
    pub twist: f64,
    /// Overlap of non-neighbouring beads (`fibre.N.self_contact`), of beads with the walls
    /// (`fibre.N.wall_contact`) and, half of each pair's, of beads with another fibre's
    /// (`fibre.N.fibre_contact`); zero without any.
    pub contact: f64,
}

impl Energies {
    /// Total elastic energy.
    pub fn total(&self) -> f64 {
        self.stretch + self.bend + self.twist + self.contact
    }
}

impl std::ops::AddAssign for Energies {
    fn add_assign(&mut self, o: Self) {
        self.stretch += o.stretch;
        self.bend += o.bend;
        self.twist += o.twist;
        self.contact += o.contact;
    }
}
