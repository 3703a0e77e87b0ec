//! A board flashed with a batch's table (model.md §10): its cap is (1 − margin) times the
//! batch's guaranteed limit, not the flashed device's own; the boot says which bound set it;
//! no command goes above it; a target only the device's own limit allows is refused.

mod common;

use common::{amplifier, made_batch_table, reference_batch};
use de_resonator::controller::CapBy;
use de_resonator::{Controller, Device, Settings, Tuner, REFERENCE_DEVICE};

#[test]
fn the_cap_is_the_batch_s() {
    let (bytes, g) = made_batch_table(&reference_batch(), 0.05, 64, 4096).unwrap();
    let own = Tuner::new(Device::new(REFERENCE_DEVICE).unwrap())
        .limit()
        .at
        .volts;
    assert!(g < 0.8 * own, "{g} vs {own}");
    let settings = Settings::for_target(45.5);
    let (mut c, boot) =
        Controller::start(REFERENCE_DEVICE.cast(), &bytes, amplifier(), settings).unwrap();
    assert_eq!(boot.cap_by, CapBy::Batch);
    let kept = boot.batch_limit_volts.unwrap();
    assert!(f64::from(kept) <= g && f64::from(kept) > g * (1.0 - 1e-7));
    let cap = f64::from(boot.max_volts);
    assert!(
        cap <= 0.95 * g && cap >= 0.95 * g * (1.0 - 1e-4),
        "{cap} vs {g}"
    );
    // Driven for a while at 45.5 Hz, with a target raised toward the batch's top: every
    // command at or below the cap.
    for _ in 0..3000 {
        let out = c.tick(Default::default());
        assert!(f64::from(out.volts) <= cap, "{} above {cap}", out.volts);
    }
    // The same device's own table: the cap by its own limit, a third higher.
    let own_table = common::made_table(REFERENCE_DEVICE, 0.05, 64);
    let (_, boot) =
        Controller::start(REFERENCE_DEVICE.cast(), &own_table, amplifier(), settings).unwrap();
    assert_eq!((boot.cap_by, boot.batch_limit_volts), (CapBy::Limit, None));
    assert!(f64::from(boot.max_volts) > 1.3 * cap);
}

/// 43.1 Hz needs 9,166 V on the reference device: inside its own limit, above the batch's
/// cap. The batch's table does not reach it: refused at boot, with the table's range.
#[test]
fn a_target_beyond_the_batch_s_cap_is_refused() {
    let (bytes, _) = made_batch_table(&reference_batch(), 0.05, 64, 4096).unwrap();
    let settings = Settings::for_target(43.1);
    let err = Controller::start(REFERENCE_DEVICE.cast(), &bytes, amplifier(), settings)
        .err()
        .unwrap();
    assert!(
        err.to_string().contains("outside the table's range"),
        "{err}"
    );
}
