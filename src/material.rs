//! Elastic materials and the effective (contact) modulus of a pair.

use crate::error::{Error, positive};

/// An isotropic elastic material.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Material {
    /// Density `rho` in kg/m^3.
    pub density_kg_m3: f32,
    /// Young's modulus `E` in Pa.
    pub modulus_pa: f32,
    /// Poisson's ratio `nu`, in `[0, 0.5)`.
    pub poisson: f32,
}

impl Material {
    /// Coal of the paper's Tables 1-2: 1380 kg/m^3, 5.3 GPa, 0.32.
    pub const COAL: Material = Material::new(1380.0, 5.3e9, 0.32);
    /// Sandstone (gangue) of the paper's Table 2: 2487 kg/m^3, 13.5 GPa, 0.123.
    pub const SANDSTONE: Material = Material::new(2487.0, 13.5e9, 0.123);
    /// Carbon-steel plate of the paper's Table 1: 7850 kg/m^3, 206 GPa, 0.28.
    pub const CARBON_STEEL: Material = Material::new(7850.0, 2.06e11, 0.28);
    /// Roof sandstone from the coal-gangue literature (physics notes, section 4): 2525 kg/m^3,
    /// 35 GPa, 0.25.
    pub const ROOF_SANDSTONE: Material = Material::new(2525.0, 35.0e9, 0.25);
    /// Sandy mudstone (physics notes, section 4): 2500 kg/m^3, 5.4 GPa, 0.15. About as stiff
    /// as coal: only the density tells them apart.
    pub const SANDY_MUDSTONE: Material = Material::new(2500.0, 5.4e9, 0.15);

    /// A material from density (kg/m^3), Young's modulus (Pa) and Poisson's ratio. Not
    /// checked here: [`Material::validate`] or any use in the model checks it.
    pub const fn new(density_kg_m3: f32, modulus_pa: f32, poisson: f32) -> Self {
        Self {
            density_kg_m3,
            modulus_pa,
            poisson,
        }
    }

    /// Checks every field: finite, density and modulus `> 0`, `0 <= nu < 0.5`.
    pub fn validate(&self) -> Result<(), Error> {
        positive(self.density_kg_m3, "density_kg_m3")?;
        positive(self.modulus_pa, "modulus_pa")?;
        if !self.poisson.is_finite() {
            return Err(Error::NonFinite("poisson"));
        }
        if !(0.0..0.5).contains(&self.poisson) {
            return Err(Error::PoissonOutOfRange);
        }
        Ok(())
    }

    /// Compliance `(1 - nu^2) / E` in 1/Pa.
    fn compliance_per_pa(&self) -> f32 {
        (1.0 - self.poisson * self.poisson) / self.modulus_pa
    }
}

/// Effective modulus of the contact (paper Eq. 6), in Pa:
/// `1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`.
///
/// The compliances are added in f32 (each is `~1e-11`, far from the f32 limits for any
/// `E` in `1e-30..1e30`).
pub fn effective_modulus_pa(a: &Material, b: &Material) -> Result<f32, Error> {
    a.validate()?;
    b.validate()?;
    let c = a.compliance_per_pa() + b.compliance_per_pa();
    crate::error::representable(1.0 / c, "effective modulus")
}
