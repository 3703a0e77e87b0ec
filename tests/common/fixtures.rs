//! Fixtures built on the core: devices and the reference's table, controller and amplifier,
//! random devices, a DAC bus and an enable line that record, a closed-loop plant on the
//! core's integrator. They set a test up; they are not what it asserts against (`oracle`).

use de_resonator::DeviceParams;

use super::oracle::first_invariant;

/// A neo-Hookean copy of the reference device.
pub fn neo_hookean_reference() -> DeviceParams<f64> {
    DeviceParams {
        jlim: None,
        ..de_resonator::REFERENCE_DEVICE
    }
}

/// A neo-Hookean device whose f(Φ) first falls, then rises past f0 (limit `emi`).
pub fn non_monotone_device() -> DeviceParams<f64> {
    DeviceParams {
        prestretch_1: 1.34,
        prestretch_2: 1.86,
        length_active: 0.0278,
        length_passive: 0.0166,
        jlim: None,
        ..de_resonator::REFERENCE_DEVICE
    }
}

/// A tuning table for `p` as `host-sim lut` makes it (the core's writer: f's turning points
/// and points evenly spaced in Φ², up to (1 − margin)·limit less the headroom).
pub fn made_table(p: DeviceParams<f64>, margin: f64, points: usize) -> Vec<u8> {
    try_made_table(p, margin, points).unwrap()
}

/// The same, or the writer's refusal (points that are not monotone in f32, on a device
/// whose frequency barely moves with the bias).
pub fn try_made_table(
    p: DeviceParams<f64>,
    margin: f64,
    points: usize,
) -> Result<Vec<u8>, de_resonator::table::TableError> {
    use de_resonator::table;
    let stored = table_points(p, margin, points);
    let mut bytes = vec![0u8; table::table_bytes(points)];
    table::write(&mut bytes, &p.cast(), margin as f32, 0.0, &stored)?;
    Ok(bytes)
}

/// The points of `p`'s table (f's turning points and points evenly spaced in Φ², up to
/// (1 − margin)·limit less the headroom).
fn table_points(p: DeviceParams<f64>, margin: f64, points: usize) -> Vec<(f32, f32)> {
    use de_resonator::{table, Device, Tuner};
    let tuner = Tuner::new(Device::new(p).unwrap());
    let m = table::table_margin(margin);
    let top = tuner.max_bias(m).unwrap();
    let mut turns = Vec::new();
    tuner
        .for_each_turning_point(m, |turn| turns.push(turn))
        .unwrap();
    let mut stored = vec![(0.0f32, 0.0f32); points];
    table::fill(tuner.device(), &top, &turns, &mut stored).unwrap();
    stored
}

/// The reference device as a batch (model.md §10): μ ±10%, H ±5%, E_B 35–200 MV/m.
pub fn reference_batch() -> de_resonator::model::tolerance::DeviceBox {
    use de_resonator::model::tolerance::{DeviceBox, Spread};
    use de_resonator::Field;
    DeviceBox::exact(de_resonator::REFERENCE_DEVICE)
        .with(Field::ShearModulus, Spread::Relative(0.1))
        .unwrap()
        .with(Field::Thickness, Spread::Relative(0.05))
        .unwrap()
        .with(
            Field::BreakdownField,
            Spread::Range {
                low: 35e6,
                high: 200e6,
            },
        )
        .unwrap()
}

/// A tuning table for the batch `b` as `host-sim lut` makes it (model.md §10): the nominal
/// device's branch up to (1 − margin)·(the guaranteed limit) less the headroom, the batch's
/// ranges (rounded outward to f32) and its guaranteed limit (rounded down) kept; version 1
/// for a batch without tolerances. Also the guaranteed limit, V. `None` where no bias is
/// safe for every device (the guaranteed limit below a thousandth of the lowest found).
/// The search has `leaves` leaves (fewer: faster, less tight, as certain).
pub fn made_batch_table(
    b: &de_resonator::model::tolerance::DeviceBox,
    margin: f64,
    points: usize,
    leaves: usize,
) -> Option<(Vec<u8>, f64)> {
    use de_resonator::model::guaranteed::Leaf;
    use de_resonator::table::TableBatch;
    use de_resonator::{table, Device, Tuner};
    let mut leaves = vec![Leaf::default(); leaves];
    let found = b.guaranteed_limit(&mut leaves).ok()?;
    let g = found.volts;
    if g <= 1e-3 * found.lowest_found_volts || g.is_nan() {
        return None;
    }
    if b.is_exact() {
        return Some((made_table(b.nominal, margin, points), g));
    }
    let own_limit = Tuner::new(Device::new(b.nominal).unwrap()).limit().at.volts;
    let own = 1.0 - (1.0 - margin) * g / own_limit;
    let stored = table_points(b.nominal, own, points);
    let top = f64::from(stored.last()?.1);
    let batch = TableBatch::of(b, g, top, &mut leaves).ok()?;
    let mut bytes = vec![0u8; table::batch_table_bytes(points)];
    table::write_batch(
        &mut bytes,
        &b.nominal.cast(),
        Some(&batch),
        margin as f32,
        0.0,
        &stored,
    )
    .unwrap();
    Some((bytes, g))
}

/// The wide-range device of the mismatch scenes (f0 34.5 Hz, limit `emi` at 8395.67 V).
pub fn wide_range_device() -> DeviceParams<f64> {
    DeviceParams {
        shear_modulus: 45e3,
        jlim: Some(120.0),
        prestretch_1: 1.5,
        prestretch_2: 3.0,
        length_passive: 0.06,
        ..de_resonator::REFERENCE_DEVICE
    }
}

/// A small deterministic generator (xorshift64), for the randomised tests and the fuzz test:
/// the same seed gives the same cases on every machine.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }

    /// Log-uniform in [a, b).
    pub fn log_range(&mut self, a: f64, b: f64) -> f64 {
        (a.ln() + (b.ln() - a.ln()) * self.unit()).exp()
    }

    /// Below `n`.
    pub fn below(&mut self, n: usize) -> usize {
        (self.unit() * n as f64) as usize % n.max(1)
    }

    /// Near-Gaussian, mean 0 and variance 1: the sum of twelve uniforms less six.
    pub fn gaussian(&mut self) -> f64 {
        (0..12).map(|_| self.unit()).sum::<f64>() - 6.0
    }
}

/// Parameters of a random device, over the ranges the tuning tests use; one case in three
/// breaks down just past the pre-stretch, one in three is nearly slack in direction 2 at
/// zero bias (λ1p·λ2p² = 1 + ε, ε from 1e-6 to 1e-2): limits within 1e-7 to 1e-3 of λ1p.
/// As f32 would hold them (cast there and back), so f32 and f64 see the same device. May
/// be invalid: callers filter with `Device::new`.
pub fn random_device(rng: &mut Rng) -> DeviceParams<f64> {
    let (l1p, l2p) = (rng.range(0.7, 4.5), rng.range(0.7, 4.5));
    let jlim = (rng.unit() < 0.5).then(|| first_invariant(l1p, l2p) + rng.range(1.0, 200.0));
    let mut p = DeviceParams {
        shear_modulus: rng.range(1e4, 1e6),
        jlim,
        relative_permittivity: rng.range(2.0, 10.0),
        density: rng.range(500.0, 2000.0),
        breakdown_field: rng.range(2e7, 3e8),
        thickness: rng.range(1e-4, 3e-3),
        length_active: rng.range(0.005, 0.06),
        length_passive: rng.range(0.005, 0.06),
        width: rng.range(0.01, 0.1),
        bar_mass: rng.range(0.0, 0.02),
        prestretch_1: l1p,
        prestretch_2: l2p,
        damping: 0.0,
    };
    match rng.below(3) {
        1 => p.breakdown_field = rng.log_range(1e4, 1e7),
        2 => p.prestretch_2 = (1.0 / l1p).sqrt() * (1.0 + rng.log_range(1e-6, 1e-2)),
        _ => {}
    }
    p.cast::<f32>().cast()
}

/// Recompute the trailing CRC-32 after editing a table or an image (both end in the CRC of
/// every byte before it), so the edit reaches the checks after the CRC.
pub fn reseal(bytes: &mut [u8]) {
    let body = bytes.len() - 4;
    let crc = de_resonator::bytes::crc32(&bytes[..body]);
    bytes[body..].copy_from_slice(&crc.to_le_bytes());
}

/// The plant for the controller's closed-loop tests: the device `p` (f64 RK4, one step a
/// tick, at rest at its pre-stretch), driven by each tick's command.
pub struct Plant {
    model: de_resonator::Integrator<f64>,
    tick_seconds: f64,
}

impl Plant {
    pub fn new(p: DeviceParams<f64>, tick_hz: f64) -> Self {
        use de_resonator::{Device, Drive, Integrator, Method, State};
        let device = Device::new(p).unwrap();
        let rest = State {
            stretch: p.prestretch_1,
            velocity: 0.0,
        };
        let drive = Drive::constant(&device, 0.0);
        let range = device.model_range();
        let model =
            Integrator::new(device, drive, Method::Rk4, 1.0 / tick_hz, range, rest, true).unwrap();
        Self {
            model,
            tick_seconds: 1.0 / tick_hz,
        }
    }

    /// The plant's parameters from now on (a plant that creeps), its state kept.
    pub fn set_params(&mut self, p: DeviceParams<f64>) {
        use de_resonator::{Device, Drive, Integrator, Method};
        let device = Device::new(p).unwrap();
        let state = self.model.state();
        let step = self.tick_seconds;
        let drive = Drive::constant(&device, 0.0);
        let range = device.model_range();
        self.model = Integrator::new(device, drive, Method::Rk4, step, range, state, true).unwrap();
    }

    /// The stretch now.
    pub fn stretch(&self) -> f64 {
        self.model.state().stretch
    }

    /// One tick at `volts`.
    pub fn step(&mut self, volts: f32) {
        let device = *self.model.device();
        let drive = de_resonator::Drive::constant(&device, f64::from(volts));
        self.model.set_drive(drive).unwrap();
        self.model.step().unwrap();
    }
}

/// `p` damped to quality factor `q` at its natural frequency at zero bias.
pub fn with_quality_factor(p: DeviceParams<f64>, q: f64) -> DeviceParams<f64> {
    use de_resonator::{Device, Tuner};
    let f0 = Tuner::new(Device::new(p).unwrap())
        .zero_bias()
        .natural_frequency_hz;
    DeviceParams {
        damping: p.effective_mass() * std::f64::consts::TAU * f0 / q,
        ..p
    }
}

/// The natural frequency of device `p` (f64 statics) at a bias of `volts`, on the branch
/// below its limit (model.md §5).
#[allow(dead_code)]
pub fn natural_hz_at(p: &DeviceParams<f64>, volts: f32) -> f64 {
    use de_resonator::{Device, Tuner};
    let device = Device::new(*p).unwrap();
    let limit = *Tuner::new(device).limit();
    let offset = device.offset_for_bias(f64::from(volts), limit.at.offset);
    device.natural_frequency_hz_at(offset.unwrap())
}

/// 0..10 kV over the full scale: a 2.5 V reference and an amplifier gain of 4000.
pub fn amplifier() -> de_resonator::Amplifier {
    de_resonator::Amplifier::new(2.5, 4000.0).unwrap()
}

/// The reference device's 64-point table as `host-sim lut` makes it (the f64 model).
pub fn reference_table() -> Vec<u8> {
    made_table(de_resonator::REFERENCE_DEVICE, 0.05, 64)
}

/// The reference device's controller (f32, as flashed) on `reference_table()` and
/// `amplifier()`.
pub fn start_reference(
    settings: de_resonator::Settings,
) -> Result<de_resonator::Controller, de_resonator::Fault> {
    let params = de_resonator::REFERENCE_DEVICE.cast::<f32>();
    de_resonator::Controller::start(params, &reference_table(), amplifier(), settings)
        .map(|(c, _)| c)
}

/// The DAC's bus: counts nothing, fails when told.
#[derive(Default)]
pub struct Bus {
    pub fails: std::cell::Cell<bool>,
}

impl embedded_hal::spi::ErrorType for &Bus {
    type Error = embedded_hal::spi::ErrorKind;
}

impl embedded_hal::spi::SpiDevice for &Bus {
    fn transaction(
        &mut self,
        _: &mut [embedded_hal::spi::Operation<'_, u8>],
    ) -> Result<(), embedded_hal::spi::ErrorKind> {
        if self.fails.get() {
            Err(embedded_hal::spi::ErrorKind::Other)
        } else {
            Ok(())
        }
    }
}

/// The amplifier's enable line.
#[derive(Default)]
pub struct Pin {
    pub high: std::cell::Cell<bool>,
}

impl embedded_hal::digital::ErrorType for &Pin {
    type Error = core::convert::Infallible;
}

impl embedded_hal::digital::OutputPin for &Pin {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.high.set(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.high.set(true);
        Ok(())
    }
}

/// The start of a reply refused with `code` (`err <n> `): the tests name codes, not numbers.
pub fn refused_with(code: de_resonator::wire::protocol::ErrorCode) -> String {
    format!("err {code} ")
}
