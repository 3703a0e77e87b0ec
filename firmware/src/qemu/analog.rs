//! QEMU emulates no ADC sampling and no DMA: no acquisition ever starts (the type the app's
//! resources and its DMA task name; `sensor` fills the tick's block instead).

use de_resonator::acquire::Block;

/// Never made under QEMU.
pub enum Acquisition {}

impl Acquisition {
    pub fn on_interrupt(&mut self, _: &mut Block) {
        match *self {}
    }
}
