//! The scene's object instances, in file order:
//!
//! ```text
//! ObjectBegin "tree" Shape "plymesh" "string filename" "tree.ply" ObjectEnd
//! AttributeBegin Translate 4 0 2 ObjectInstance "tree" AttributeEnd
//! ```
//!
//! A million instances are common, so each is 104 bytes: the top three rows of
//! world-from-instance in f64, its object, and the index of what few instances have
//! (a bottom row other than exactly 0 0 0 1, or motion) in a side list. A boxed
//! optional part took 112 bytes an instance (8 MB more a million).

use crate::math::animated::AnimatedTransform;
use glam::{DAffine3, DMat4, DVec4};

/// One instance's record.
#[derive(Clone, Debug, PartialEq)]
struct InstanceDesc {
    /// The top three rows of world-from-instance.
    affine: DAffine3,
    object: u32,
    /// Its entry in [`Instances::rare`], or [`NONE`].
    rare: u32,
}

const NONE: u32 = u32::MAX;

/// The most instances a scene may hold: the accelerator numbers them in 31 bits.
pub const MAX_INSTANCES: usize = 1 << 31;
const _: () = assert!(std::mem::size_of::<InstanceDesc>() == 104);

/// What few instances have.
#[derive(Clone, Debug, Default, PartialEq)]
struct InstanceRare {
    bottom: Option<DVec4>,
    motion: Option<AnimatedTransform>,
}

/// The instances of a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Instances {
    list: Vec<InstanceDesc>,
    rare: Vec<InstanceRare>,
}

/// One instance as [`Instances::get`] reads it.
#[derive(Clone, Copy, Debug)]
pub struct Placed<'a> {
    desc: &'a InstanceDesc,
    rare: Option<&'a InstanceRare>,
}

impl Instances {
    /// Appends an instance of `object` placed by `world_from_instance` (its start
    /// transform when it moves), stored so that [`Placed::world_from_instance`] gives it
    /// back bit for bit. The list grows into huge pages ([`crate::hugepages::push`]).
    pub fn push(&mut self, object: u32, world_from_instance: DMat4, motion: Option<AnimatedTransform>) {
        let bottom = world_from_instance.row(3);
        let plain = bottom.to_array().map(f64::to_bits) == DVec4::W.to_array().map(f64::to_bits);
        let bottom = (!plain).then_some(bottom);
        let rare = match bottom.is_some() || motion.is_some() {
            true => self.add_rare(InstanceRare { bottom, motion }),
            false => NONE,
        };
        let desc = InstanceDesc { affine: DAffine3::from_mat4(world_from_instance), object, rare };
        crate::hugepages::push(&mut self.list, desc);
    }

    /// How many the list has room for.
    pub fn capacity(&self) -> usize {
        self.list.capacity()
    }

    /// Whether the list has no room left.
    pub fn is_full(&self) -> bool {
        self.list.len() == self.list.capacity()
    }

    /// Makes room for `additional` more, in one step (marked for huge pages, as
    /// [`crate::hugepages::push`] grows it).
    pub fn reserve(&mut self, additional: usize) {
        crate::hugepages::reserve(&mut self.list, additional);
    }

    fn add_rare(&mut self, rare: InstanceRare) -> u32 {
        self.rare.push(rare);
        (self.rare.len() - 1) as u32
    }

    pub fn len(&self) -> usize {
        self.list.len()
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Instance `k`, in file order.
    pub fn get(&self, k: usize) -> Placed<'_> {
        self.placed(&self.list[k])
    }

    fn placed<'a>(&'a self, desc: &'a InstanceDesc) -> Placed<'a> {
        Placed { desc, rare: self.rare.get(desc.rare as usize) }
    }

    pub fn iter(&self) -> impl ExactSizeIterator<Item = Placed<'_>> + '_ {
        self.list.iter().map(|d| self.placed(d))
    }

    pub fn par_iter(&self) -> impl rayon::iter::IndexedParallelIterator<Item = Placed<'_>> + '_ {
        use rayon::prelude::*;
        self.list.par_iter().map(|d| self.placed(d))
    }

    /// Replaces every instance's object `o` by `remap(o)`, on all threads.
    pub fn remap_objects(&mut self, remap: impl Fn(u32) -> u32 + Sync) {
        use rayon::prelude::*;
        self.list.par_iter_mut().for_each(|d| d.object = remap(d.object));
    }

    /// Animates instance `k` by `motion`.
    pub fn set_motion(&mut self, k: usize, motion: AnimatedTransform) {
        match self.list[k].rare {
            NONE => self.list[k].rare = self.add_rare(InstanceRare { bottom: None, motion: Some(motion) }),
            r => self.rare[r as usize].motion = Some(motion),
        }
    }
}

impl<'a> Placed<'a> {
    pub fn object(&self) -> u32 {
        self.desc.object
    }

    /// World-from-instance (the start transform of a moving instance).
    pub fn world_from_instance(&self) -> DMat4 {
        let mut m = DMat4::from(self.desc.affine);
        if let Some(bottom) = self.rare.and_then(|r| r.bottom) {
            (m.x_axis.w, m.y_axis.w, m.z_axis.w, m.w_axis.w) = bottom.into();
        }
        m
    }

    /// The top three rows of [`Placed::world_from_instance`].
    pub fn world_from_instance_affine(&self) -> DAffine3 {
        self.desc.affine
    }

    /// Its motion between the `TransformTimes`, when its transform is animated.
    pub fn motion(&self) -> Option<&'a AnimatedTransform> {
        self.rare.and_then(|r| r.motion.as_ref())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn bits(m: DMat4) -> [u64; 16] {
        m.to_cols_array().map(f64::to_bits)
    }

    #[test]
    fn instances_give_back_their_matrix_bit_for_bit() {
        let plain = DMat4::from_scale_rotation_translation(
            DVec3::new(1.5, 2.0, 0.25),
            glam::DQuat::from_rotation_y(0.3),
            DVec3::new(-4.0, 0.5, 7.0),
        );
        let mut negative_zero = plain;
        negative_zero.x_axis.w = -0.0;
        let mut projective = plain;
        projective.z_axis.w = 0.5;
        projective.w_axis.w = 2.0;
        let mut all = Instances::default();
        for m in [plain, negative_zero, projective] {
            all.push(1, m, None);
        }
        for (k, m) in [plain, negative_zero, projective].into_iter().enumerate() {
            assert_eq!(bits(all.get(k).world_from_instance()), bits(m));
            assert_eq!(all.get(k).object(), 1);
        }
        assert_eq!(all.rare.len(), 2, "a plain matrix needs no side entry");
        assert!(all.get(0).rare.is_none());
    }

    #[test]
    fn motion_keeps_the_bottom_row_and_the_others_their_own() {
        let mut m = DMat4::IDENTITY;
        m.y_axis.w = 0.125;
        let mut all = Instances::default();
        all.push(3, DMat4::IDENTITY, None);
        all.push(3, m, None);
        all.push(4, DMat4::IDENTITY, None);
        let motion = AnimatedTransform::new(DMat4::IDENTITY, DMat4::IDENTITY, [0.0, 1.0]);
        all.set_motion(1, motion.clone());
        all.set_motion(2, motion);
        assert!(all.get(0).motion().is_none());
        assert!(all.get(1).motion().is_some() && all.get(2).motion().is_some());
        assert_eq!(bits(all.get(1).world_from_instance()), bits(m));
        assert_eq!(bits(all.get(2).world_from_instance()), bits(DMat4::IDENTITY));
        all.remap_objects(|o| o * 10);
        assert_eq!(all.iter().map(|p| p.object()).collect::<Vec<_>>(), [30, 30, 40]);
    }
}
