//! `declare_faults!`: the one list of faults (`super`) made into everything a fault is: the
//! enum, its number and key (`FAULT_KEYS`), its stage, its words (`Display`) and its figures
//! for the fault log (`Fault::figures`, `Fault::from_figures`). Adding a fault is one entry.
//!
//! An entry: the variant's docs, its name and fields (one unnamed field given a name for its
//! words, or named fields of a type named by one word, as `f32` (so that `defmt`'s derive sees
//! the type itself and formats it as such), or none), `= number "key" Stage`, and `=> |f| words`: an
//! expression writing the sentence to the formatter `f`, the fields bound by reference. The
//! figures hold the fields in the order written (indices and numbers each in their own
//! order: `figures::Figure`), so an entry's fields are part of the log's layout: a field is
//! only ever added at the end.

macro_rules! declare_faults {
    (
        $(#[$meta:meta])*
        pub enum Fault {
            $(
                $(#[$variant_meta:meta])*
                $variant:ident
                $( ( $inner:ident : $inner_ty:ty ) )?
                $( { $( $(#[$field_meta:meta])* $field:ident : $field_ty:ident ),* $(,)? } )?
                = $number:literal $key:literal $stage:ident
                => |$f:ident| $words:expr;
            )*
        }
    ) => {
        $(#[$meta])*
        pub enum Fault {
            $(
                $(#[$variant_meta])*
                $variant $( ($inner_ty) )? $( { $( $(#[$field_meta])* $field: $field_ty ),* } )?,
            )*
        }

        /// Each fault's key, in the order of its number: `Fault::number` − 1 indexes it (the
        /// telemetry record and the fault log carry the number, a reader shows the key).
        pub const FAULT_KEYS: [&str; [$($number),*].len()] = [$($key),*];

        // The numbers run 1, 2, 3, … in the list's order: a new fault takes the next one,
        // none is ever renumbered (a gap or a swap fails to compile).
        const _: () = {
            let numbers: &[u8] = &[$($number),*];
            let mut rest = numbers;
            let mut next = 1;
            while let [first, more @ ..] = rest {
                assert!(*first == next, "fault numbers out of order");
                next += 1;
                rest = more;
            }
        };

        impl Fault {
            /// The fault's kind as a number from 1 (0: no fault, in a record).
            pub fn number(&self) -> u8 {
                match self {
                    $( Fault::$variant { .. } => $number, )*
                }
            }

            /// The key of fault number `number` (`Fault::number`), if one has it.
            pub fn key_of(number: u8) -> Option<&'static str> {
                FAULT_KEYS.get(usize::from(number).checked_sub(1)?).copied()
            }

            /// Whether this is a boot refusal or a trip while running. A trim's retune runs
            /// the boot's checks again while running: its boot-kind refusals stop a running
            /// drive.
            pub fn stage(&self) -> FaultStage {
                match self {
                    $( Fault::$variant { .. } => FaultStage::$stage, )*
                }
            }

            /// What the fault log keeps of this fault.
            pub fn figures(&self) -> Figures {
                let mut put = Put::new(self.number());
                match self {
                    $(
                        Fault::$variant $( ($inner) )? $( { $($field),* } )? => {
                            $( $inner.put(&mut put); )?
                            $( $( $field.put(&mut put); )* )?
                        }
                    )*
                }
                put.figures()
            }

            /// The fault its figures were made of; `None` if they are not a fault's.
            pub fn from_figures(figures: &Figures) -> Option<Fault> {
                let take = &mut Take::new(figures);
                Some(match figures.number {
                    $(
                        $number => Fault::$variant
                            $( ({ let $inner = Figure::take(take)?; $inner }) )?
                            $( { $( $field: Figure::take(take)? ),* } )?,
                    )*
                    _ => return None,
                })
            }
        }

        #[cfg(test)]
        impl Fault {
            /// One fault of each kind, in the order of their numbers, each field a different
            /// value (`tests::Sample`): the tests cover a new fault with no more written.
            pub(super) fn samples() -> [Fault; FAULT_KEYS.len()] {
                let mut k = 0u32;
                let mut next = || {
                    k += 1;
                    k
                };
                [$(
                    Fault::$variant
                        $( ({ let $inner = Sample::sample(next()); $inner }) )?
                        $( { $( $field: Sample::sample(next()) ),* } )?,
                )*]
            }
        }

        impl core::fmt::Display for Fault {
            fn fmt(&self, formatter: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                match self {
                    $(
                        #[allow(unused_variables)]
                        Fault::$variant $( ($inner) )? $( { $($field),* } )? => {
                            let $f = &mut *formatter;
                            $words
                        }
                    )*
                }
            }
        }
    };
}

pub(super) use declare_faults;
