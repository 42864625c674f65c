//! A performer's edit of a show's effect chain, applied as a control event: the show rebuilt with
//! the chain edited and switched to like a reload (unchanged nodes keep their instance, state and
//! values). A live show builds it ahead on a worker thread ([`SceneInstance::prepare_chain_edit`],
//! then [`SceneInstance::offer_prepared`]); a render builds it when the event is applied. Either
//! way it takes effect at the step the event is applied before, so a recording replays it exactly.

use std::sync::mpsc::Receiver;

use super::SceneInstance;
use super::rebuild::{Replacement, SceneSnapshot, Transitions};
use crate::assets::Assets;
use crate::gpu::Gpu;
use crate::params::{EffectEdit, Remap, ShowCommand};
use crate::scene::show::chain_edit::{chain_owner, edited_show, in_chain};

impl SceneInstance {
    /// Builds what chain edit `edit` of `layer`'s chain (`None`: the master's) makes of
    /// `snapshot`'s show: its effects' pipelines compiled, ready to install.
    pub fn prepare_chain_edit(
        snapshot: &SceneSnapshot,
        gpu: &Gpu,
        assets: &Assets,
        output_size: (u32, u32),
        (layer, edit): (Option<usize>, EffectEdit),
    ) -> Result<Replacement, String> {
        let scene = edited_show(assets, &snapshot.scene, &snapshot.params, layer, edit)?;
        let owner = chain_owner(layer);
        // Its transitions are the running show's, unless the edit added the show's first effect
        // or removed its last (the dry/wet mix is a transition the show has only with effects).
        let transitions = match (&scene.show, &snapshot.scene.show) {
            (Some(new), Some(old)) if new.plays_same_transitions(old) => Transitions::TakeRunning,
            _ => Transitions::Compile,
        };
        // The chain's effects are built anew: an effect moved to another place is another node.
        let rebuild = |n: &crate::scene::SceneNode| in_chain(&n.id, &owner);
        Replacement::prepare(snapshot, scene, gpu, assets, output_size, (&rebuild, transitions))
            .map_err(|e| e.to_string())
    }

    /// Starts building chain edit `command` ahead on a worker thread, from a snapshot of the show
    /// now; its result arrives on the receiver (offer it with [`Self::offer_prepared`]).
    pub fn build_ahead(&self, command: ShowCommand) -> Result<Receiver<Result<Replacement, String>>, String> {
        let ShowCommand::Effect { layer, edit } = command else {
            return Err(format!("{command:?} is not a chain edit"));
        };
        let (gpu, assets, size) =
            self.show_context().ok_or_else(|| format!("{command:?}: '{}' is a scene, not a show", self.scene.name))?;
        let snapshot = self.snapshot();
        let (sender, receiver) = std::sync::mpsc::channel();
        crate::gpu::spawn_worker("indra-chain-edit", move || {
            let _ = sender.send(Self::prepare_chain_edit(&snapshot, &gpu, &assets, size, (layer, edit)));
        })
        .map_err(|e| format!("no thread to build the edit on: {e}"))?;
        Ok(receiver)
    }

    /// What a show builds with — the device, the assets and the output size — for building a
    /// chain edit ahead (`None` for a scene).
    pub fn show_context(&self) -> Option<(Gpu, Assets, (u32, u32))> {
        let (gpu, assets, size) = self.show.as_ref()?.context();
        Some((gpu.clone(), assets.clone(), size))
    }

    /// Offers a chain edit built ahead: when `command` is applied, `replacement` is installed
    /// (if the scene is still the one it was built from) instead of building it then.
    pub fn offer_prepared(&mut self, command: ShowCommand, replacement: Replacement) {
        self.prepared = Some((command, replacement));
    }

    /// Where every parameter went since the last call, if chain edits replaced the scene: for
    /// everything outside the instance that holds parameter positions (queued events, the
    /// control maps, MIDI learn).
    pub fn take_replaced(&mut self) -> Option<Remap> {
        self.replaced.take()
    }

    /// Applies chain edit `command` (told in the messages when it cannot be applied).
    pub(super) fn edit_chain(&mut self, command: ShowCommand) {
        let ShowCommand::Effect { layer, edit } = command else { return };
        let Some(show) = &self.show else {
            self.messages.push(format!("{command:?}: '{}' is a scene, not a show", self.scene.name));
            return;
        };
        let (gpu, assets, size) = show.context();
        let (gpu, assets) = (gpu.clone(), assets.clone());
        let prepared = self.prepared.take().filter(|(c, _)| *c == command).map(|(_, r)| r);
        let started = std::time::Instant::now();
        let installed = prepared.map(|r| self.install(r));
        log::debug!("chain edit installed in {:.3} ms", started.elapsed().as_secs_f64() * 1e3);
        let remap = match installed {
            Some(Ok(remap)) => remap,
            // Not built ahead, or built for a scene that has changed since: built now.
            _ => {
                let built = Self::prepare_chain_edit(&self.snapshot(), &gpu, &assets, size, (layer, edit));
                match built.map(|r| self.install(r).expect("built from this revision")) {
                    Ok(remap) => remap,
                    Err(e) => {
                        self.messages.push(format!("the effect edit was refused: {e}"));
                        return;
                    }
                }
            }
        };
        log::info!("{}'s effect chain: {edit:?}", chain_owner(layer));
        self.replaced = Some(match self.replaced.take() {
            Some(before) => before.then(&remap),
            None => remap,
        });
    }
}
