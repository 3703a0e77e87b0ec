//! `declare_commands!`: the one table of the command port's requests (`super`) made into
//! everything a request is: the `Command` enum, `COMMANDS` (name, form, what it does: `help`
//! and the typo's suggestion read it), `HELP`, [`parse`](super::parse), whether it only reads
//! (`Command::reads_only`), its rule (`Command::rule`), and `Board::run`, which calls its
//! handler. Adding a command is one entry.
//!
//! An entry: the variant's docs, its name and fields (unnamed fields given names, or named
//! fields, or none), `= "name" "form" "what it does"`, then
//! - `rule Rule`: what must hold before the handler runs (`Rule`);
//! - `reads expr`: whether the request changes nothing (a connection that does not control a
//!   board may send it), the fields bound;
//! - `parse |args| expr` (left out: a request of no arguments): the command from its
//!   arguments (`wire::protocol::Args`);
//! - `run |board, request| expr`: its handler, the fields bound, giving what the command task
//!   does next (`Then`).

macro_rules! declare_commands {
    (
        $(#[$meta:meta])*
        pub enum Command {
            $(
                $(#[doc = $doc:literal])*
                $variant:ident
                $( ( $( $inner:ident : $inner_ty:ty ),* ) )?
                $( { $( $field:ident : $field_ty:ty ),* $(,)? } )?
                = $name:literal $form:literal $does:literal
                rule $rule:ident
                reads $reads:expr,
                $( parse |$args:ident| $parse:expr, )?
                run |$board:ident, $request:ident| $run:expr;
            )*
        }
    ) => {
        $(#[$meta])*
        pub enum Command {
            $(
                $(#[doc = $doc])*
                $variant $( ( $($inner_ty),* ) )? $( { $( $field: $field_ty ),* } )?,
            )*
        }

        /// Every command: its name, its form and what it does (`help <command>` says the two,
        /// `help` the forms), in the order `help` lists them.
        pub const COMMANDS: [CommandInfo; [$($name),*].len()] = [
            $( CommandInfo { form: $form, does: $does }, )*
        ];

        // Each form starts with its command's name (what `CommandInfo::name` reads).
        const _: () = { $( assert!(names($form, $name), "a form names its command"); )* };

        /// Each command's docs (its variant's), by line, in the order of `COMMANDS`: the docs'
        /// table of requests (docs/commands.md) is written from them.
        pub const COMMAND_DOCS: [&[&str]; COMMANDS.len()] = [ $( &[$($doc),*], )* ];

        /// Each command's rule, in the order of `COMMANDS`.
        pub const COMMAND_RULES: [Rule; COMMANDS.len()] = [ $( Rule::$rule, )* ];

        impl Command {
            /// The command's name, as typed.
            pub fn name(&self) -> &'static str {
                match self {
                    $( Command::$variant { .. } => $name, )*
                }
            }

            /// Whether the request changes nothing on the board (or is `stop`, an emergency
            /// stop any connection may give): what a connection that does not control the
            /// board may send.
            pub fn reads_only(&self) -> bool {
                match *self {
                    $(
                        #[allow(unused_variables)]
                        Command::$variant $( ( $($inner),* ) )? $( { $($field),* } )? => $reads,
                    )*
                }
            }
        }

        /// The command of name `name`, its arguments read from `args` (the words after it).
        fn command(name: &str, args: &mut Args) -> Result<Command, ParseError> {
            match name {
                $( $name => Ok(declare_commands!(@parse $variant $( |$args| $parse )? ; args)), )*
                _ => Err(ParseError::UnknownCommand {
                    nearest: nearest_name(name, &COMMANDS, CommandInfo::name).map(|(_, n)| n),
                }),
            }
        }

        impl Command {
            /// What must hold before the command's handler runs.
            pub fn rule(&self) -> Rule {
                match self {
                    $( Command::$variant { .. } => Rule::$rule, )*
                }
            }
        }

        impl<K: Keeper> Board<'_, K> {
            /// Answer `command` into `request.out` by its handler (its rule checked before).
            fn run(&mut self, command: Command, request: &mut Request<impl Shared>) -> Then {
                match command {
                    $(
                        #[allow(unused_variables)]
                        Command::$variant $( ( $($inner),* ) )? $( { $($field),* } )? => {
                            let $board = &mut *self;
                            let $request = &mut *request;
                            $run
                        }
                    )*
                }
            }
        }
    };
    (@parse $variant:ident ; $args:ident) => { Command::$variant };
    (@parse $variant:ident |$bound:ident| $parse:expr ; $args:ident) => {{
        let $bound = &mut *$args;
        $parse
    }};
}

pub(super) use declare_commands;
