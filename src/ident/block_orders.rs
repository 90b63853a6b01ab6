//! The structural order of each block: one setting for both (the contract's `"order": 0` or
//! `"order": "auto"`), or one per block (`"order": {"gyro": 0, "accel": "auto"}`; a block left
//! out of the object is `"auto"`). Written back as the single value when both blocks agree, so a
//! file that gave one order keeps its form.

use std::fmt;

use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize, Serializer};

use super::settings::{MAX_ORDER, OrderSetting};
use crate::block::Block;

/// The order setting of each block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockOrders {
    /// The gyro block's order.
    pub gyro: OrderSetting,
    /// The accelerometer block's order.
    pub accel: OrderSetting,
}

impl Default for BlockOrders {
    fn default() -> Self {
        Self::both(OrderSetting::Auto)
    }
}

impl From<OrderSetting> for BlockOrders {
    fn from(order: OrderSetting) -> Self {
        Self::both(order)
    }
}

impl BlockOrders {
    /// The same setting for both blocks.
    #[must_use]
    pub const fn both(order: OrderSetting) -> Self {
        Self {
            gyro: order,
            accel: order,
        }
    }

    /// The setting of `block`.
    #[must_use]
    pub fn of(&self, block: Block) -> OrderSetting {
        match block {
            Block::Gyro => self.gyro,
            Block::Accel => self.accel,
        }
    }

    /// The setting of `block`, to change.
    pub fn of_mut(&mut self, block: Block) -> &mut OrderSetting {
        match block {
            Block::Gyro => &mut self.gyro,
            Block::Accel => &mut self.accel,
        }
    }

    /// The setting both blocks share, if they do.
    #[must_use]
    pub fn common(&self) -> Option<OrderSetting> {
        (self.gyro == self.accel).then_some(self.gyro)
    }
}

impl fmt::Display for OrderSetting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OrderSetting::Auto => f.write_str("auto"),
            OrderSetting::Fixed(n) => write!(f, "{n}"),
        }
    }
}

impl fmt::Display for BlockOrders {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.common() {
            Some(order) => write!(f, "{order}"),
            None => write!(f, "gyro {}, accel {}", self.gyro, self.accel),
        }
    }
}

impl Serialize for BlockOrders {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if let Some(order) = self.common() {
            return order.serialize(s);
        }
        let mut map = s.serialize_map(Some(2))?;
        for block in Block::BOTH {
            map.serialize_entry(block.name(), &self.of(block))?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for BlockOrders {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = BlockOrders;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(
                    f,
                    "an order 0..={MAX_ORDER}, \"auto\", or one per block ({{\"gyro\": 0, \"accel\": \"auto\"}})"
                )
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<BlockOrders, E> {
                OrderSetting::deserialize(de::value::U64Deserializer::new(v)).map(BlockOrders::both)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<BlockOrders, E> {
                OrderSetting::deserialize(de::value::I64Deserializer::new(v)).map(BlockOrders::both)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<BlockOrders, E> {
                OrderSetting::deserialize(de::value::StrDeserializer::new(v)).map(BlockOrders::both)
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<BlockOrders, A::Error> {
                let mut orders = BlockOrders::default();
                while let Some(key) = map.next_key::<String>()? {
                    let Some(block) = Block::BOTH.into_iter().find(|b| b.name() == key) else {
                        return Err(de::Error::custom(format!(
                            "order: unknown block \"{key}\" (known: gyro, accel)"
                        )));
                    };
                    *orders.of_mut(block) = map.next_value()?;
                }
                Ok(orders)
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<BlockOrders, String> {
        serde_json::from_str(text).map_err(|e| e.to_string())
    }

    #[test]
    fn one_order_or_one_per_block_and_back() {
        assert_eq!(parse("2"), Ok(BlockOrders::both(OrderSetting::Fixed(2))));
        assert_eq!(parse("\"auto\""), Ok(BlockOrders::default()));
        let per_block = parse(r#"{"accel": 1}"#).unwrap_or_default();
        assert_eq!(per_block.of(Block::Accel), OrderSetting::Fixed(1));
        assert_eq!(per_block.of(Block::Gyro), OrderSetting::Auto, "left out: auto");
        assert_eq!(
            serde_json::to_string(&per_block).ok().as_deref(),
            Some(r#"{"gyro":"auto","accel":1}"#)
        );
        assert_eq!(
            serde_json::to_string(&BlockOrders::both(OrderSetting::Fixed(0)))
                .ok()
                .as_deref(),
            Some("0"),
            "the contract's single value when both agree"
        );
        assert_eq!(per_block.to_string(), "gyro auto, accel 1");
    }

    #[test]
    fn bad_orders_are_refused_with_the_reason() {
        let err = |text: &str| parse(text).err().unwrap_or_default();
        assert!(err("5").contains("above 4"), "{}", err("5"));
        assert!(err("-1").contains("negative"));
        assert!(err(r#"{"gyro": 9}"#).contains("above 4"));
        assert!(err(r#"{"magnetometer": 0}"#).contains("unknown block \"magnetometer\""));
        assert!(err(r#"{"gyro": "best"}"#).contains("not \"best\""));
        assert!(err("[0, 1]").contains("one per block"));
    }
}
